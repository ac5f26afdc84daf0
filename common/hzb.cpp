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

bool DepthPyramid::occludes(const PyramidProbe& p) const {
  if (p.kind != PyramidProbe::Kind::probe || p.level >= levels_.size()) return false;
  const Level& l = levels_[p.level];
  for (int y = p.y0; y <= p.y1; ++y)
    for (int x = p.x0; x <= p.x1; ++x)
      if (!(p.depth < l.d[size_t(y) * l.w + x])) return false;
  return true;
}

uint32_t pyramid_level_count(const Viewport& vp) {
  uint32_t n = 1;
  for (int w = vp.width, h = vp.height; w > 1 || h > 1; w = (w + 1) / 2, h = (h + 1) / 2) ++n;
  return n;
}

uint32_t pyramid_level_for(int x0, int y0, int x1, int y1, uint32_t levels, int span) {
  uint32_t l = 0;
  while (l + 1 < levels && ((x1 >> l) - (x0 >> l) >= span || (y1 >> l) - (y0 >> l) >= span)) ++l;
  return l;
}

PyramidProbe pyramid_probe(const Aabb& box, const Camera& cam, const Viewport& vp, double relative_pad, int span) {
  PyramidProbe p;
  if (box.empty()) {
    p.kind = PyramidProbe::Kind::no_samples;
    return p;
  }
  // The box as BoxQuerier draws it: camera-relative, padded.
  const glm::dvec3 lo = box.min - cam.eye, hi = box.max - cam.eye;
  const glm::dvec3 far = glm::max(glm::abs(lo), glm::abs(hi));
  const double pad = relative_pad * std::max({far.x, far.y, far.z});
  const glm::dvec3 plo = lo - pad, phi = hi + pad;
  const glm::dmat4 vpm = cam.projection() * cam.view_rotation();
  double xmin = 1e300, xmax = -1e300, ymin = 1e300, ymax = -1e300, zmax = -1e300, wmin = 1e300;
  for (int i = 0; i < 8; ++i) {
    const glm::dvec3 c{(i & 1) ? phi.x : plo.x, (i & 2) ? phi.y : plo.y, (i & 4) ? phi.z : plo.z};
    const glm::dvec4 clip = vpm * glm::dvec4(c, 1.0);
    // In front of the near plane with room to spare: no clipping at the near plane on the GPU.
    if (!(clip.w >= cam.near_dist * (1.0 + 1e-3))) return p;
    xmin = std::min(xmin, clip.x / clip.w);
    xmax = std::max(xmax, clip.x / clip.w);
    ymin = std::min(ymin, clip.y / clip.w);
    ymax = std::max(ymax, clip.y / clip.w);
    zmax = std::max(zmax, clip.z / clip.w);
    wmin = std::min(wmin, clip.w);
  }
  if (!(xmax >= -1 && xmin <= 1 && ymax >= -1 && ymin <= 1 && zmax >= 0)) return p;  // a query decides
  auto to_px = [](double ndc, int size) { return (ndc * 0.5 + 0.5) * size; };
  const int px0 = std::max(0, int(std::floor(to_px(xmin, vp.width))) - 1);
  const int px1 = std::min(vp.width - 1, int(std::ceil(to_px(xmax, vp.width))) + 1);
  const int py0 = std::max(0, int(std::floor(to_px(ymin, vp.height))) - 1);
  const int py1 = std::min(vp.height - 1, int(std::ceil(to_px(ymax, vp.height))) + 1);
  if (px0 > px1 || py0 > py1) return p;
  // The GPU computes clip z as the sum of terms of size |p22| and |p32| / w: its float rounding
  // is relative to those, not to the (possibly much smaller) depth near the far plane.
  const glm::dmat4 proj = cam.projection();
  const double terms = std::abs(proj[2][2]) + std::abs(proj[3][2]) / wmin;
  const double bound = zmax + 1e-3 * std::abs(zmax) + 1e-5 * terms;
  const uint32_t level = pyramid_level_for(px0, py0, px1, py1, pyramid_level_count(vp), span);
  p.kind = PyramidProbe::Kind::probe;
  p.level = level;
  p.x0 = px0 >> level;
  p.y0 = py0 >> level;
  p.x1 = px1 >> level;
  p.y1 = py1 >> level;
  // Rounded up to float (the pyramid holds floats): the bound stays a bound.
  p.depth = std::nextafter(float(bound), 2.0f);
  return p;
}

}  // namespace occ
