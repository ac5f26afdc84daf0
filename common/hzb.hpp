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

class DepthPyramid {
 public:
  // depth: width*height floats, row 0 at the bottom (glReadPixels order).
  void build(const std::vector<float>& depth, int width, int height);
  // Conservative: false only if every pixel of the footprint has an occluder strictly in front
  // of the box's nearest point.
  bool may_be_visible(const BoxFootprint& fp) const;
  bool may_be_visible(const Aabb& box, const Camera& cam) const {
    return may_be_visible(box_footprint(box, cam, {width(), height()}));
  }
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

}  // namespace occ
