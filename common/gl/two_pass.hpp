// Frames the render client culls for itself (occlusion only where it pays; used by
// render_client/client.cpp). When the switch sends a frustum set (its gate found that occlusion
// does not pay there: the OR would draw the visible set a second time, on the same two cores) or
// no switch node serves, the render client draws the frame in two passes against the frame's own
// depth, for one depth read-back:
//   1. the renderables that showed the last time (all of them the first time; seed(): e.g. the
//      switch's last visible set), in one draw call;
//   2. the depth read back into a DepthPyramid; each other renderable is drawn unless the pyramid
//      proves its box hidden (DepthPyramid::hides: no fragment of it could pass the depth test),
//      or its node's parent's (tried first, once a frame: a street of hidden blocks costs a few
//      proofs, not one per leaf).
// The depth only comes nearer after pass 1, so whatever pass 1's depth hides is hidden in the
// frame: the frame is the one-pass frame of the whole set (CHC-like coherence, without waiting
// on any query). Except at exact depth ties between a pass-2 and a pass-1 draw (coplanar faces):
// one draw call orders those by its sort (scene_renderer.hpp), two calls by pass. That matters
// only for a pass-2 renderable whose box meets the box of a pass-1 renderable it may come before
// in that order (draw_places): one GL_EQUAL occlusion query of those against
// pass 1's depth finds any tie; their screen rectangles are then drawn again in one pass
// (scissored: everything whose box reaches them, in the set's order): frames stay pixel-exact.
// What showed is learned from the same pyramid: pass 1's renderables are tested after pass 2 is
// submitted (while llvmpipe rasterises it; their own depth never hides them), pass 2's showed.
#pragma once
#include <cstdint>
#include <span>
#include <vector>

#include "common/camera.hpp"
#include "common/gl/context.hpp"
#include "common/gl/scene_renderer.hpp"
#include "common/scene/hierarchy.hpp"
#include "common/cull/hzb.hpp"
#include "common/lod/lod_select.hpp"

namespace occ {

class TwoPassDrawer {
 public:
  // Texels a box's proof may visit (DepthPyramid::occludes_refined) before it counts as shown.
  static constexpr int kProofTexels = 64;
  // Flush parts while drawing a frame (FlushSchedule::request): pass 1's depth is
  // read back once llvmpipe has rasterised its last part, so small parts keep that wait short.
  // Triangles a part; chosen by measurement (paired runs on llvmpipe).
  static constexpr uint32_t kFlushTriangles = 4000;

  // The context, renderer, hierarchy and renderables outlive the drawer.
  TwoPassDrawer(GlContext& ctx, SceneRenderer& renderer, const Hierarchy& h, const Renderables& r);
  ~TwoPassDrawer();
  TwoPassDrawer(const TwoPassDrawer&) = delete;
  TwoPassDrawer& operator=(const TwoPassDrawer&) = delete;

  struct Frame {
    DrawStats drawn;          // everything drawn (twice over for a frame drawn again)
    uint64_t set_triangles = 0;  // the triangles of the whole set: what one pass would draw
    uint32_t first = 0;       // renderables drawn in pass 1
    uint32_t second = 0;      // drawn in pass 2
    uint32_t hidden = 0;      // proven hidden: not drawn
    bool redrawn = false;     // a depth tie between the passes: its rectangle drawn again
    uint64_t redrawn_pixels = 0;  // the rectangle's pixels
  };
  // Draws the Shaded frame of renderables `ids` for `cam`, complete (glFinish), as
  // begin_frame(cam, true) + draw_renderables(ids) would.
  Frame draw(const Camera& cam, std::span<const uint32_t> ids);
  // Frames were drawn otherwise meanwhile: the next draw() starts with everything shown
  // (forget), or with what showed in the last of them (seed: e.g. the switch's visible set).
  void forget();
  void seed(std::span<const uint32_t> shown_ids);
  // Where renderable `id`'s opaque and MASK Shaded draws fall in the order of one
  // draw_renderables call of this frame (the renderer's begin_frame eye): its first and its
  // last place. Places of different renderables compare as their draws would be ordered; a
  // renderable with no such draws gets {max, min}, before and after nothing. Draws nothing.
  struct DrawPlace {
    SceneRenderer::DrawOrder order;
    uint64_t collected = 0;  // the renderable's collection rank (first item << 8 | level), then draw
    auto operator<=>(const DrawPlace&) const = default;
  };
  std::pair<DrawPlace, DrawPlace> draw_places(uint32_t id);
  // The renderables the last draw() drew in its two passes (the set less those proven hidden).
  void drawn_ids(std::vector<uint32_t>& out) const {
    out.assign(first_.begin(), first_.end());
    out.insert(out.end(), second_.begin(), second_.end());
  }

 private:
  GlContext& ctx_;
  SceneRenderer& renderer_;
  const Hierarchy& h_;
  const Renderables& r_;
  DepthPyramid pyramid_;
  std::vector<uint8_t> shown_;  // per renderable: showed when it was last in a set
  // This frame's proofs per hierarchy node (0: not tried): a node inside a hidden one is hidden,
  // so a renderable's ancestors are tried first, each once a frame (node_hidden).
  enum : uint8_t { kHidden = 1, kShown = 2 };
  std::vector<uint8_t> memo_;
  std::vector<uint32_t> touched_;
  bool node_hidden(uint32_t node, const Camera& cam);
  // The steps of draw(): pass 2's candidates less what pass 1's depth hides; the pass-2
  // renderables that may tie with pass 1 (checked_); the screen rectangle of a found tie (empty:
  // x0 > x1); that rectangle drawn again in one pass.
  void drop_hidden(const Camera& cam, Frame& f);
  void find_tie_candidates();
  struct Rect {
    int x0, y0, x1, y1;
  };
  Rect tie_rectangle(const Camera& cam);
  void redraw(const Camera& cam, std::span<const uint32_t> ids, const Rect& rect, Frame& f);
  std::vector<uint32_t> first_, second_, checked_, redraw_;
  std::vector<DrawPlace> first_last_;  // per pass-1 renderable: its last draw's place
  std::vector<SceneRenderer::DrawOrder> orders_;  // draw_places' scratch
  GLuint tie_query_ = 0;
};

}  // namespace occ
