// A software hierarchical Z pyramid (Greene et al. 1993), as used by the depth-readback
// occlusion server ("Distributed GigaWalk" in the paper's section 5): the occluders' depth is
// read back, reduced into a pyramid of farthest depths, and boxes are tested against it on the
// CPU. No GL here: the caller supplies the depth buffer.
//
// Depth convention: reverse-Z as rendered by occswitch (1 = near plane, 0 = far / cleared), so
// "farther" is smaller. Level 0 holds the depth buffer; each texel of level k+1 holds the
// minimum (farthest) of the up to 2x2 texels below it. A box is occluded when its nearest depth is
// strictly smaller (farther) than the farthest occluder depth over every texel its screen
// rectangle touches: conservative, like an occlusion query that needs one passing sample.
#pragma once
#include <algorithm>
#include <cstdint>
#include <vector>

#include "common/camera.hpp"
#include "common/math.hpp"

namespace occ {

// The screen footprint of a box: pixel rectangle (inclusive) and nearest reverse-Z depth.
struct BoxFootprint {
  enum class Kind { Offscreen, NearPlane, OnScreen } kind = Kind::Offscreen;
  int x0 = 0, y0 = 0, x1 = -1, y1 = -1;  // pixels, row 0 at the bottom (GL order)
  float nearest_depth = 0;               // max reverse-Z depth of the corners
};

// Projects the 8 corners camera-relative in double. NearPlane: some corner is not in front of the
// near plane (the caller must treat the box as visible). Offscreen: the rectangle misses the
// viewport or the box lies beyond the far plane.
BoxFootprint box_footprint(const Aabb& box, const Camera& cam, const Viewport& vp);

// Pixels [x0, x1] x [y0, y1] of a viewport (inclusive; empty when x0 > x1) that grow with what is
// drawn: where a depth pyramid is behind its depth buffer after occluder fusion drew.
struct PixelRect {
  int x0 = 0, y0 = 0, x1 = -1, y1 = -1;
  bool empty() const { return x0 > x1 || y0 > y1; }
  void clear() { *this = PixelRect{}; }
  void add(const PixelRect& r) {
    if (r.empty()) return;
    if (empty()) {
      *this = r;
      return;
    }
    x0 = std::min(x0, r.x0), y0 = std::min(y0, r.y0), x1 = std::max(x1, r.x1), y1 = std::max(y1, r.y1);
  }
  // Where a draw inside `box` may touch the viewport: its footprint, the whole viewport where
  // the near plane cuts the box, nothing where it is off screen.
  void add_box(const Aabb& box, const Camera& cam, const Viewport& vp) {
    const BoxFootprint fp = box_footprint(box, cam, vp);
    if (fp.kind == BoxFootprint::Kind::NearPlane) add({0, 0, vp.width - 1, vp.height - 1});
    if (fp.kind == BoxFootprint::Kind::OnScreen) add({fp.x0, fp.y0, fp.x1, fp.y1});
  }
  // Whether `fp` (not off screen) may touch these pixels.
  bool touches(const BoxFootprint& fp) const {
    if (empty() || fp.kind == BoxFootprint::Kind::Offscreen) return false;
    return fp.kind == BoxFootprint::Kind::NearPlane || !(fp.x1 < x0 || fp.x0 > x1 || fp.y1 < y0 || fp.y0 > y1);
  }
  double pixels() const { return empty() ? 0.0 : double(x1 - x0 + 1) * double(y1 - y0 + 1); }
};

// ---- The switch nodes' HC pyramid test (GPU side in common/gl/hzb_query.*): the same
// pyramid, built on the GPU from HC's own depth buffer, proves boxes occluded before any occlusion
// query is issued; boxes it cannot prove occluded get a real query. Everything but the texel reads
// is decided here, on the CPU and without GL, so that it is unit tested.
//
// Precision: a box is proven occluded only if no fragment of its occlusion query
// (common/gl/box_query.hpp: the box padded by `relative_pad` of its farthest corner coordinate,
// camera-relative, front faces, depth test GL_GREATER) could pass. Its fragments lie inside the
// padded box's projected rectangle (widened by a pixel each side) and are at most as near as its
// nearest corner; `depth` adds a margin (1e-3 relative plus the float rounding of the projection)
// for the GPU's float transform and depth interpolation. A box whose padded corners are not all in
// front of the near plane by a margin is clipped there by the GPU: its fragments come from the part
// of the box (padded by at least the query's pad) inside the view volume, so that part's vertices
// give the rectangle and the nearest depth (box_in_view_vertices; fragments at the clipped edge
// have depth 1 when it is on screen, and then nothing is proven). When the rectangle misses the
// viewport, or the part is empty, a real query decides.
struct PyramidProbe {
  enum class Kind : uint8_t {
    no_samples,  // an empty box: its query draws nothing (0 samples)
    query,       // the pyramid cannot decide: a real occlusion query
    probe,       // occluded iff depth < every texel of [x0, x1] x [y0, y1] at `level`
  } kind = Kind::query;
  uint32_t level = 0;
  int32_t x0 = 0, y0 = 0, x1 = -1, y1 = -1;  // texels of `level` (at most span x span), row 0 at the bottom
  float depth = 0;                           // bound on the nearest depth a query fragment can have
};

class DepthPyramid {
 public:
  // depth: width*height floats, row 0 at the bottom (glReadPixels order).
  void build(const std::vector<float>& depth, int width, int height);
  // The same in two steps without a copy: level 0's storage (width*height floats, row 0 at the
  // bottom) for the caller to fill, e.g. by glReadPixels straight into it, then build_levels().
  // Memory is reused from build to build of one size.
  float* level0(int width, int height);
  void build_levels();
  // After level 0 changed only inside pixels [x0, x1] x [y0, y1]: the texels above them.
  void build_levels(int x0, int y0, int x1, int y1);
  // Conservative: false only if every pixel of the footprint has an occluder strictly in front
  // of the box's nearest point.
  bool may_be_visible(const BoxFootprint& fp) const;
  bool may_be_visible(const Aabb& box, const Camera& cam) const {
    return may_be_visible(box_footprint(box, cam, {width(), height()}));
  }
  // The CPU twin of the GPU pyramid test (common/gl/hzb_query.*): true when every texel of the
  // probe's rectangle at its level lies strictly in front of probe.depth. Only for Kind::probe.
  bool occludes(const PyramidProbe& p) const;
  // A finer proof of the same claim (no fragment of the box's occlusion query could pass): true
  // where occludes(p) is, and also when every texel of the probe's rectangle, followed down the
  // pyramid, ends in texels where the part of the padded box inside the texel's pixels (widened
  // by a pixel each side) is strictly behind the texel's farthest depth (with the probe's depth
  // margin) or absent. A box's nearest depth over one texel is often much farther than its
  // nearest corner: thin, slanted and large boxes are proven where the probe is not (on a plant
  // walk it proves clearly more of the boxes whose queries count 0 samples). Gives up (false) at a
  // pixel it cannot prove, after max_texels texels, and for boxes within 1e-3 of the near plane
  // that the probe does not prove. Only for Kind::probe.
  bool occludes_refined(const PyramidProbe& p, const Aabb& box, const Camera& cam, double relative_pad,
                        int max_texels = 256) const;
  // Whether geometry inside `box` drawn with depth test GL_GREATER (reverse-Z) would leave no
  // fragment on this depth buffer: an empty box, or its occlusion query's probe
  // (pyramid_probe with `relative_pad`) proven by occludes_refined. False proves nothing (boxes
  // at the near plane, off screen or in view).
  bool hides(const Aabb& box, const Camera& cam, double relative_pad, int max_texels = 64) const;
  // The converse, from level 0 alone: true when an occlusion query of `box` against this very
  // depth buffer would count a sample (common/gl/box_query.hpp: the box padded, front faces,
  // GL_GREATER). Up to samples_per_axis^2 pixel centres spread over the box's screen rectangle
  // are tried, those under the farthest texels of a coarse level first: a pixel whose centre's
  // ray enters the box through the inside of a face (1/64 pixel from its edges: the rasteriser
  // covers that centre, all the more with the query's padded box) and whose depth is strictly
  // farther than the entry point, less the margin of pyramid_probe() for the GPU's float
  // transform and interpolation, is a sample the query would count (the padded box's front face
  // on that ray is at least as near), if the padded box's entry point is in front of the near
  // plane (by 1e-3: the GPU does not clip the face there). Boxes crossing the near plane are
  // sampled over the screen rectangle of their part in front of it. False proves nothing.
  bool shows(const Aabb& box, const Camera& cam, int samples_per_axis = 8) const;
  int width() const { return levels_.empty() ? 0 : levels_[0].w; }
  int height() const { return levels_.empty() ? 0 : levels_[0].h; }
  size_t level_count() const { return levels_.size(); }
  // Farthest depth of texel (x, y) of a level (for tests).
  float texel(size_t level, int x, int y) const { return levels_[level].d[size_t(y) * levels_[level].w + x]; }

 private:
  struct Level {
    int w, h;
    std::vector<float> d;
  };
  std::vector<Level> levels_;
};

// Levels of a viewport's pyramid: level 0 is the viewport, level k+1 halves level k (rounding up)
// until 1 x 1. Texel (x, y) of level k covers pixels [x 2^k, (x+1) 2^k) x [y 2^k, (y+1) 2^k).
uint32_t pyramid_level_count(const Viewport& vp);
// The lowest level (below `levels`) at which the inclusive pixel rectangle spans at most
// span x span texels.
uint32_t pyramid_level_for(int x0, int y0, int x1, int y1, uint32_t levels, int span = 2);
PyramidProbe pyramid_probe(const Aabb& box, const Camera& cam, const Viewport& vp, double relative_pad, int span = 2);
// The vertices (clip coordinates, w > 0) of the part of the camera-relative box [lo, hi] inside the
// view volume (in front of the near plane, within the four side planes; vpm = projection x view
// rotation): where the GPU's fragments of a box crossing the near plane come from. Empty when
// that part is empty (or degenerate).
std::vector<glm::dvec4> box_in_view_vertices(const glm::dvec3& lo, const glm::dvec3& hi, const glm::dmat4& vpm,
                                             double near_dist);

}  // namespace occ
