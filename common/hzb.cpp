#include "common/hzb.hpp"

#include <algorithm>
#include <cmath>

namespace occ {

BoxFootprint box_footprint(const Aabb& box, const Camera& cam, const Viewport& vp) {
  BoxFootprint fp;
  if (box.empty()) return fp;
  const glm::dmat4 vpm = cam.projection() * cam.view_rotation();
  double xmin = 1e300, xmax = -1e300, ymin = 1e300, ymax = -1e300, zmax = -1e300;
  for (int i = 0; i < 8; ++i) {
    glm::dvec3 c{(i & 1) ? box.max.x : box.min.x, (i & 2) ? box.max.y : box.min.y, (i & 4) ? box.max.z : box.min.z};
    glm::dvec4 clip = vpm * glm::dvec4(c - cam.eye, 1.0);
    // clip.w is the distance along the view direction; in front of the near plane means w >= near.
    if (!(clip.w >= cam.near_dist)) {
      fp.kind = BoxFootprint::Kind::NearPlane;
      return fp;
    }
    const double x = clip.x / clip.w, y = clip.y / clip.w, z = clip.z / clip.w;
    xmin = std::min(xmin, x);
    xmax = std::max(xmax, x);
    ymin = std::min(ymin, y);
    ymax = std::max(ymax, y);
    zmax = std::max(zmax, z);
  }
  if (xmax < -1 || xmin > 1 || ymax < -1 || ymin > 1 || zmax < 0) return fp;  // off screen / beyond far
  auto to_px = [](double ndc, int size) { return (ndc * 0.5 + 0.5) * size; };
  // Inclusive pixel range whose centres could be covered, widened by one pixel for rounding.
  fp.x0 = std::max(0, int(std::floor(to_px(xmin, vp.width))) - 1);
  fp.x1 = std::min(vp.width - 1, int(std::ceil(to_px(xmax, vp.width))) + 1);
  fp.y0 = std::max(0, int(std::floor(to_px(ymin, vp.height))) - 1);
  fp.y1 = std::min(vp.height - 1, int(std::ceil(to_px(ymax, vp.height))) + 1);
  if (fp.x0 > fp.x1 || fp.y0 > fp.y1) return fp;
  fp.kind = BoxFootprint::Kind::OnScreen;
  fp.nearest_depth = float(std::min(zmax, 1.0));
  return fp;
}

void DepthPyramid::build(const std::vector<float>& depth, int width, int height) {
  levels_.clear();
  levels_.push_back({width, height, depth});
  while (levels_.back().w > 1 || levels_.back().h > 1) {
    const Level& lo = levels_.back();
    Level up{(lo.w + 1) / 2, (lo.h + 1) / 2, {}};
    up.d.resize(size_t(up.w) * up.h);
    for (int y = 0; y < up.h; ++y)
      for (int x = 0; x < up.w; ++x) {
        float m = 1.0f;
        for (int dy = 0; dy < 2; ++dy)
          for (int dx = 0; dx < 2; ++dx) {
            const int sx = 2 * x + dx, sy = 2 * y + dy;
            if (sx < lo.w && sy < lo.h) m = std::min(m, lo.d[size_t(sy) * lo.w + sx]);
          }
        up.d[size_t(y) * up.w + x] = m;
      }
    levels_.push_back(std::move(up));
  }
}

bool DepthPyramid::may_be_visible(const BoxFootprint& fp) const {
  if (fp.kind == BoxFootprint::Kind::NearPlane) return true;
  if (fp.kind == BoxFootprint::Kind::Offscreen || levels_.empty()) return fp.kind != BoxFootprint::Kind::Offscreen;
  // The coarsest level at which the rectangle spans at most 2x2 texels... then every texel it
  // touches must hide the box.
  const int span = std::max(fp.x1 - fp.x0, fp.y1 - fp.y0) + 1;
  size_t level = 0;
  while (level + 1 < levels_.size() && (span >> level) > 2) ++level;
  const Level& l = levels_[level];
  const int x0 = fp.x0 >> level, x1 = fp.x1 >> level, y0 = fp.y0 >> level, y1 = fp.y1 >> level;
  for (int y = y0; y <= std::min(y1, l.h - 1); ++y)
    for (int x = x0; x <= std::min(x1, l.w - 1); ++x)
      if (!(fp.nearest_depth < l.d[size_t(y) * l.w + x])) return true;
  return false;
}

}  // namespace occ
