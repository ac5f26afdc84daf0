// How the render client draws a frame's set: the switch's visible set in one pass; a frustum set
// (the switch culled without occlusion, or no node serves) in two passes against the frame's own
// depth where the two-pass gate measures that they pay (common/gl/two_pass.hpp); and the
// window's O overlay of what occlusion culling removed.
#pragma once
#include <cstdint>
#include <memory>
#include <vector>

#include "common/gl/box_overlay.hpp"
#include "common/gl/startup.hpp"
#include "common/gl/two_pass.hpp"
#include "common/cull/occlusion_gate.hpp"
#include "render_client/options.hpp"

namespace occ {

class FrameDrawer {
 public:
  // `g` outlives the drawer.
  FrameDrawer(const ClientOptions& o, SceneGl& g);

  struct Drawn {
    DrawStats st;             // everything drawn
    TwoPassDrawer::Frame tp;  // two passes: what each did (else empty)
    bool frustum_set = false;
    bool two_pass = false;
    bool held = false;  // a frustum set drawn the way the two-pass gate last decided, its trials held
    // Whether the frame shows what its set costs the way the two-pass gate last decided (not a
    // trial of the other way): a sample for the occlusion gate.
    bool representative = true;
    // The set's triangles: what one pass draws (two passes may draw fewer).
    uint64_t set_triangles() const { return two_pass ? tp.set_triangles : st.triangles; }
  };
  // Draws `ids` (renderables) with camera `cam`, finished (glFinish); `frustum_set`: a set the
  // switch did not cull with occlusion. `hold`: the occlusion gate is measuring frames without
  // occlusion (OcclusionGate::measuring_without): frustum sets are drawn the way the two-pass
  // gate last decided, and its trials wait (one experiment at a time).
  Drawn draw(const Camera& cam, const std::vector<uint32_t>& ids, bool frustum_set, bool hold = false);
  // A frame drawn by draw() took `render_ms` to show: the two-pass gate's measure.
  void measured(const Drawn& d, double render_ms);
  // What the last draw() drew: `ids` less what two passes proved hidden.
  std::vector<uint32_t> drawn_ids(const Drawn& d, const std::vector<uint32_t>& ids) const;
  // An item buffer of renderables `ids` with camera `cam` (--images items): each pixel the id of
  // the item (leaf, any level) or HLOD that drew it (SceneRenderer::draw_renderables, ItemIds).
  // Leaves the frame buffer holding it.
  Image item_buffer(const Camera& cam, const std::vector<uint32_t>& ids);
  std::vector<float> depth() const { return g_.ctx->read_depth(); }  // of what was drawn last
  // The O overlay: tints the boxes of the leaves in the frustum that occlusion culling removed
  // over the frame just drawn; returns how many.
  size_t draw_overlay(const Camera& cam, const std::vector<uint32_t>& visible_ids);
  // The log line of the frustum sets and how they were drawn (nothing when there were none).
  void print_summary() const;

 private:
  SceneGl& g_;
  // Frustum sets culled here (--occlusion): on = two passes, off = one; measured by render time.
  // It starts with one pass (what the occlusion gate's first windows measure frames without
  // occlusion in) and tries two passes after a full window of it.
  OcclusionGate gate_;
  TwoPassDrawer two_pass_;
  std::unique_ptr<BoxOverlay> overlay_;  // --window, O
  bool two_pass_last_ = false, switch_culled_last_ = false;
  std::vector<uint32_t> last_visible_;  // the last visible set the switch culled with occlusion
  uint32_t frames_ = 0, used_ = 0, redrawn_ = 0;  // frustum sets; drawn in two passes; drawn again
};

}  // namespace occ
