#include "common/cull/hzb.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#ifdef __SSE2__
#include <immintrin.h>
#endif
#include <stdexcept>
#include <string>

namespace occ {

namespace {
// Corner i of the box [lo, hi]: bit 0 picks x, bit 1 y, bit 2 z from hi.
glm::dvec3 corner(const glm::dvec3& lo, const glm::dvec3& hi, int i) {
  return {(i & 1) ? hi.x : lo.x, (i & 2) ? hi.y : lo.y, (i & 4) ? hi.z : lo.z};
}
}  // namespace

BoxFootprint box_footprint(const Aabb& box, const Camera& cam, const Viewport& vp) {
  BoxFootprint fp;
  if (box.empty()) return fp;
  const glm::dmat4 vpm = cam.projection() * cam.view_rotation();
  double xmin = 1e300, xmax = -1e300, ymin = 1e300, ymax = -1e300, zmax = -1e300;
  for (int i = 0; i < 8; ++i) {
    glm::dvec4 clip = vpm * glm::dvec4(corner(box.min, box.max, i) - cam.eye, 1.0);
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
  if (depth.size() != size_t(std::max(width, 0)) * size_t(std::max(height, 0)))
    throw std::invalid_argument("DepthPyramid::build: " + std::to_string(depth.size()) + " depths for " +
                                std::to_string(width) + "x" + std::to_string(height));
  std::copy(depth.begin(), depth.end(), level0(width, height));
  build_levels();
}

float* DepthPyramid::level0(int width, int height) {
  if (width < 1 || height < 1)
    throw std::invalid_argument("DepthPyramid: viewport " + std::to_string(width) + "x" + std::to_string(height));
  if (levels_.empty() || levels_[0].w != width || levels_[0].h != height) {
    levels_.clear();
    for (int w = width, h = height;; w = (w + 1) / 2, h = (h + 1) / 2) {
      levels_.push_back({w, h, std::vector<float>(size_t(w) * size_t(h))});
      if (w == 1 && h == 1) break;
    }
  }
  return levels_[0].d.data();
}

void DepthPyramid::build_levels() {
  // Each texel the minimum of its up to 2 x 2 texels below; a missing last row or column repeats
  // the one before it (the minimum is unchanged). Four texels at a time with SSE (g++ -O2 does
  // not vectorise the plain loops).
  for (size_t k = 1; k < levels_.size(); ++k) {
    const Level& lo = levels_[k - 1];
    Level& up = levels_[k];
    const int pairs = lo.w / 2;  // texels of `up` with two columns below
    for (int y = 0; y < up.h; ++y) {
      const float* r0 = lo.d.data() + size_t(2 * y) * lo.w;
      const float* r1 = lo.d.data() + size_t(std::min(2 * y + 1, lo.h - 1)) * lo.w;
      float* out = up.d.data() + size_t(y) * up.w;
      int x = 0;
#ifdef __SSE2__
      for (; x + 4 <= pairs; x += 4) {
        const __m128 v0 = _mm_min_ps(_mm_loadu_ps(r0 + 2 * x), _mm_loadu_ps(r1 + 2 * x));
        const __m128 v1 = _mm_min_ps(_mm_loadu_ps(r0 + 2 * x + 4), _mm_loadu_ps(r1 + 2 * x + 4));
        _mm_storeu_ps(out + x, _mm_min_ps(_mm_shuffle_ps(v0, v1, _MM_SHUFFLE(2, 0, 2, 0)),
                                          _mm_shuffle_ps(v0, v1, _MM_SHUFFLE(3, 1, 3, 1))));
      }
#endif
      for (; x < pairs; ++x)
        out[x] = std::min(std::min(r0[2 * x], r0[2 * x + 1]), std::min(r1[2 * x], r1[2 * x + 1]));
      if (pairs < up.w) out[pairs] = std::min(r0[2 * pairs], r1[2 * pairs]);
    }
  }
}

void DepthPyramid::build_levels(int x0, int y0, int x1, int y1) {
  for (size_t k = 1; k < levels_.size(); ++k) {
    const Level& lo = levels_[k - 1];
    Level& up = levels_[k];
    x0 >>= 1, y0 >>= 1, x1 >>= 1, y1 >>= 1;
    for (int y = y0; y <= std::min(y1, up.h - 1); ++y)
      for (int x = x0; x <= std::min(x1, up.w - 1); ++x) {
        const int sx1 = std::min(2 * x + 1, lo.w - 1), sy1 = std::min(2 * y + 1, lo.h - 1);
        const float* r0 = lo.d.data() + size_t(2 * y) * lo.w;
        const float* r1 = lo.d.data() + size_t(sy1) * lo.w;
        up.d[size_t(y) * up.w + x] = std::min(std::min(r0[2 * x], r0[sx1]), std::min(r1[2 * x], r1[sx1]));
      }
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

namespace {

// Screen bounds (NDC) and the nearest depth and w of a set of clip-space points.
struct ClipBounds {
  double xmin = 1e300, xmax = -1e300, ymin = 1e300, ymax = -1e300, zmax = -1e300, wmin = 1e300;
  void add(const glm::dvec4& c) {
    xmin = std::min(xmin, c.x / c.w);
    xmax = std::max(xmax, c.x / c.w);
    ymin = std::min(ymin, c.y / c.w);
    ymax = std::max(ymax, c.y / c.w);
    zmax = std::max(zmax, c.z / c.w);
    wmin = std::min(wmin, c.w);
  }
  bool empty() const { return !(xmax >= xmin); }
};

// The camera-relative box [lo, hi]'s corners when all are at least `front` along the view axis;
// otherwise the vertices of the box [clo, chi] inside the view volume with the near plane at
// `near` (box_in_view_vertices; empty bounds when nothing is).
ClipBounds clip_bounds(const glm::dvec3& lo, const glm::dvec3& hi, const glm::dmat4& vpm, double front,
                       const glm::dvec3& clo, const glm::dvec3& chi, double near) {
  ClipBounds b;
  for (int i = 0; i < 8; ++i) {
    const glm::dvec4 clip = vpm * glm::dvec4(corner(lo, hi, i), 1.0);
    if (!(clip.w >= front)) {
      b = {};
      for (const glm::dvec4& v : box_in_view_vertices(clo, chi, vpm, near)) b.add(v);
      return b;
    }
    b.add(clip);
  }
  return b;
}

}  // namespace

bool DepthPyramid::shows(const Aabb& box, const Camera& cam, int samples_per_axis) const {
  if (box.empty() || levels_.empty() || samples_per_axis < 1) return false;
  const Level& l0 = levels_[0];
  const glm::dvec3 lo = box.min - cam.eye, hi = box.max - cam.eye;  // camera-relative, as drawn
  const glm::dmat4 proj = cam.projection();
  const glm::dmat4 vpm = proj * cam.view_rotation();
  // The screen rectangle of the box's part in front of the near plane (plus margin).
  const double near_w = cam.near_dist * (1.0 + 1e-3);
  const ClipBounds b = clip_bounds(lo, hi, vpm, near_w, lo, hi, near_w);
  if (b.empty()) return false;  // nothing in front of the near plane
  const double xmin = b.xmin, xmax = b.xmax, ymin = b.ymin, ymax = b.ymax, zmax = b.zmax;
  auto to_px = [](double ndc, int size) { return (ndc * 0.5 + 0.5) * size; };
  const int x0 = std::max(0, int(std::floor(to_px(xmin, l0.w)))), x1 = std::min(l0.w - 1, int(std::floor(to_px(xmax, l0.w))));
  const int y0 = std::max(0, int(std::floor(to_px(ymin, l0.h)))), y1 = std::min(l0.h - 1, int(std::floor(to_px(ymax, l0.h))));
  if (x0 > x1 || y0 > y1) return false;
  const glm::dmat4 inv = glm::inverse(vpm);
  // A pixel's size in world units per unit of distance (the smaller of its two sides).
  const double pixel = 2.0 * std::tan(cam.fovy_rad * 0.5) * std::min(1.0 / l0.h, cam.aspect / l0.w);
  // Twice the most the query pads the box (box_query.cpp: 1e-5 of the farthest coordinate, or
  // 4 sub-pixel steps of at least 1/16 pixel at the farthest corner): its front face on a ray lies
  // between the entry points of the box and of the box padded by this.
  const glm::dvec3 far = glm::max(glm::abs(lo), glm::abs(hi));
  const double pad = 2.0 * std::max(1e-5 * std::max({far.x, far.y, far.z}),
                                    0.25 * 2.0 * std::tan(cam.fovy_rad * 0.5) / l0.h * glm::length(far));
  // Whether the query would count pixel (px, py): its centre's ray enters the box through the
  // inside of a face, at least 1/64 pixel from the face's edges (the query's box is padded
  // outwards besides), the padded box's entry point is in front of the near plane (the face is
  // not clipped there), and the box's entry point, less the depth margin, is nearer than the
  // depth there.
  auto sample = [&](int px, int py) {
    const glm::dvec4 r = inv * glm::dvec4((px + 0.5) / l0.w * 2.0 - 1.0, (py + 0.5) / l0.h * 2.0 - 1.0, 0.5, 1.0);
    const glm::dvec3 d = glm::dvec3(r) / r.w;  // a point on the pixel centre's ray (the eye at 0)
    double t0 = 0;
    int entry = -1;
    for (int a = 0; a < 3; ++a) {
      if (d[a] == 0) continue;
      const double ta = std::min(lo[a] / d[a], hi[a] / d[a]);
      if (ta > t0) t0 = ta, entry = a;
    }
    if (entry < 0) return false;
    const glm::dvec3 at = t0 * d;
    const double margin = glm::length(at) * pixel / 64.0;
    for (int a = 0; a < 3; ++a)
      if (a != entry && !(lo[a] + margin < at[a] && at[a] < hi[a] - margin)) return false;
    double tp = -1e300;
    for (int a = 0; a < 3; ++a)
      if (d[a] != 0) tp = std::max(tp, std::min((lo[a] - pad) / d[a], (hi[a] + pad) / d[a]));
    if (!(tp > 0) || !((vpm * glm::dvec4(tp * d, 1.0)).w >= near_w)) return false;
    const glm::dvec4 c = vpm * glm::dvec4(at, 1.0);
    const double z = c.z / c.w;
    const double terms = std::abs(proj[2][2]) + std::abs(proj[3][2]) / c.w;
    return z - 1e-3 * std::abs(z) - 1e-5 * terms > double(l0.d[size_t(py) * l0.w + px]);
  };
  // First where the depth is farthest: the texels of a coarse level over the rectangle, farthest
  // first, each followed down to the farthest pixel below it (no pixel under a texel at least as
  // near as the box's nearest corner can show).
  const uint32_t level = pyramid_level_for(x0, y0, x1, y1, uint32_t(levels_.size()), 4);
  struct Texel { float d; int x, y; };
  Texel found[16];
  int n = 0;
  const Level& lc = levels_[level];
  for (int y = y0 >> level; y <= (y1 >> level); ++y)
    for (int x = x0 >> level; x <= (x1 >> level) && n < 16; ++x) {
      const float d = lc.d[size_t(y) * lc.w + x];
      if (double(d) < zmax) found[n++] = {d, x, y};
    }
  std::sort(found, found + n, [](const Texel& a, const Texel& b) { return a.d < b.d; });
  for (int k = 0; k < std::min(n, 4); ++k) {
    int x = found[k].x, y = found[k].y;
    for (uint32_t l = level; l > 0; --l) {
      const Level& below = levels_[l - 1];
      int bx = 2 * x, by = 2 * y;
      float best = 2.0f;
      for (int dy = 0; dy < 2; ++dy)
        for (int dx = 0; dx < 2; ++dx) {
          const int cx = 2 * x + dx, cy = 2 * y + dy;
          if (cx < below.w && cy < below.h && below.d[size_t(cy) * below.w + cx] < best) {
            best = below.d[size_t(cy) * below.w + cx];
            bx = cx;
            by = cy;
          }
        }
      x = bx;
      y = by;
    }
    if (x >= x0 && x <= x1 && y >= y0 && y <= y1 && sample(x, y)) return true;
  }
  // Then a grid over the rectangle.
  const int nx = std::min(samples_per_axis, x1 - x0 + 1), ny = std::min(samples_per_axis, y1 - y0 + 1);
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      // The pixel at the middle of cell (i, j) of an nx x ny grid over the rectangle.
      const int px = x0 + int((int64_t(2 * i + 1) * (x1 - x0 + 1)) / (2 * nx));
      const int py = y0 + int((int64_t(2 * j + 1) * (y1 - y0 + 1)) / (2 * ny));
      if (sample(px, py)) return true;
    }
  return false;
}

namespace {

// The nearest reverse-Z depth (max z/w) of the camera-relative box [lo, hi] inside the part of
// the view volume over NDC [xa, xb] x [ya, yb]; -inf when the two do not meet. The maximum of z/w
// (a linear-fractional function) over that convex set is at one of its vertices: a box corner
// inside the sub-frustum, a box edge crossing one of its four side planes, or one of its four edge
// rays entering the box. The caller has every corner in front of the near plane.
struct SubFrustumDepth {
  glm::dvec3 lo, hi;
  glm::dmat4 vpm, inv;
  glm::dvec4 corners[8];  // clip coordinates of the box's corners
  explicit SubFrustumDepth(const glm::dvec3& l, const glm::dvec3& h, const glm::dmat4& m) : lo(l), hi(h), vpm(m) {
    inv = glm::inverse(m);
    for (int i = 0; i < 8; ++i) corners[i] = vpm * glm::dvec4(corner(lo, hi, i), 1.0);
  }
  double nearest(double xa, double xb, double ya, double yb) const {
    double best = -std::numeric_limits<double>::infinity();
    auto inside = [&](const glm::dvec4& c) {
      const double e = 1e-12 * c.w;
      return c.x >= xa * c.w - e && c.x <= xb * c.w + e && c.y >= ya * c.w - e && c.y <= yb * c.w + e;
    };
    for (const glm::dvec4& c : corners)
      if (inside(c)) best = std::max(best, c.z / c.w);
    // Box edges against the side planes x = a w, y = a w (clip coordinates are linear along an edge).
    static constexpr int kEdges[12][2] = {{0, 1}, {2, 3}, {4, 5}, {6, 7}, {0, 2}, {1, 3},
                                          {4, 6}, {5, 7}, {0, 4}, {1, 5}, {2, 6}, {3, 7}};
    for (const auto& e : kEdges) {
      const glm::dvec4 &c0 = corners[e[0]], &c1 = corners[e[1]];
      for (int plane = 0; plane < 4; ++plane) {
        const int axis = plane >> 1;
        const double a = plane == 0 ? xa : plane == 1 ? xb : plane == 2 ? ya : yb;
        const double f0 = c0[axis] - a * c0.w, f1 = c1[axis] - a * c1.w;
        if ((f0 > 0) == (f1 > 0) || f0 == f1) continue;
        const double t = f0 / (f0 - f1);
        const glm::dvec4 c = c0 + t * (c1 - c0);
        if (inside(c)) best = std::max(best, c.z / c.w);
      }
    }
    // The sub-frustum's four edge rays entering the box (slabs; the eye is outside the box).
    for (int k = 0; k < 4; ++k) {
      const glm::dvec4 r = inv * glm::dvec4((k & 1) ? xb : xa, (k & 2) ? yb : ya, 0.5, 1.0);
      const glm::dvec3 d = glm::dvec3(r) / r.w;
      double t0 = 0, t1 = std::numeric_limits<double>::infinity();
      for (int a = 0; a < 3 && t0 <= t1; ++a) {
        if (d[a] == 0) {
          if (!(lo[a] <= 0 && 0 <= hi[a])) t0 = 1, t1 = 0;
          continue;
        }
        const double u = lo[a] / d[a], v = hi[a] / d[a];
        t0 = std::max(t0, std::min(u, v));
        t1 = std::min(t1, std::max(u, v));
      }
      if (t0 <= t1 && t0 > 0) {
        const glm::dvec4 c = vpm * glm::dvec4(t0 * d, 1.0);
        best = std::max(best, c.z / c.w);
      }
    }
    return best;
  }
};

}  // namespace

bool DepthPyramid::occludes_refined(const PyramidProbe& p, const Aabb& box, const Camera& cam, double relative_pad,
                                    int max_texels) const {
  if (p.kind != PyramidProbe::Kind::probe || p.level >= levels_.size() || box.empty()) return false;
  if (occludes(p)) return true;
  const glm::dvec3 lo = box.min - cam.eye, hi = box.max - cam.eye;
  const glm::dvec3 far = glm::max(glm::abs(lo), glm::abs(hi));
  const double pad = relative_pad * std::max({far.x, far.y, far.z});
  const glm::dmat4 proj = cam.projection();
  const SubFrustumDepth sub(lo - pad, hi + pad, proj * cam.view_rotation());
  double wmin = std::numeric_limits<double>::infinity();
  for (const glm::dvec4& c : sub.corners) wmin = std::min(wmin, c.w);
  if (!(wmin >= cam.near_dist * (1.0 + 1e-3))) return false;  // clipped at the near plane
  const double terms = std::abs(proj[2][2]) + std::abs(proj[3][2]) / wmin;
  const int w = width(), h = height();
  int budget = max_texels;
  // Texel (x, y) of `level`: proven, or followed into its children.
  auto proven = [&](auto&& self, uint32_t level, int x, int y) -> bool {
    if (--budget < 0) return false;
    const Level& l = levels_[level];
    const double xa = double((x << level) - 1) / w * 2.0 - 1.0, xb = double(std::min((x + 1) << level, w) + 1) / w * 2.0 - 1.0;
    const double ya = double((y << level) - 1) / h * 2.0 - 1.0, yb = double(std::min((y + 1) << level, h) + 1) / h * 2.0 - 1.0;
    const double z = sub.nearest(xa, xb, ya, yb);
    if (z == -std::numeric_limits<double>::infinity()) return true;  // no part of the box there
    const float bound = std::nextafter(float(z + 1e-3 * std::abs(z) + 1e-5 * terms), 2.0f);
    if (bound < l.d[size_t(y) * l.w + x]) return true;
    if (level == 0) return false;
    const Level& below = levels_[level - 1];
    for (int cy = 2 * y; cy <= std::min(2 * y + 1, below.h - 1); ++cy)
      for (int cx = 2 * x; cx <= std::min(2 * x + 1, below.w - 1); ++cx)
        if (!self(self, level - 1, cx, cy)) return false;
    return true;
  };
  for (int y = p.y0; y <= p.y1; ++y)
    for (int x = p.x0; x <= p.x1; ++x)
      if (!proven(proven, p.level, x, y)) return false;
  return true;
}

bool DepthPyramid::hides(const Aabb& box, const Camera& cam, double relative_pad, int max_texels) const {
  const PyramidProbe p = pyramid_probe(box, cam, {width(), height()}, relative_pad);
  return p.kind == PyramidProbe::Kind::no_samples || occludes_refined(p, box, cam, relative_pad, max_texels);
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

std::vector<glm::dvec4> box_in_view_vertices(const glm::dvec3& lo, const glm::dvec3& hi, const glm::dmat4& vpm,
                                             double near_dist) {
  // The convex set's planes as n.p <= d: the box's six, w >= near, -w <= x, y <= w (clip = vpm p).
  struct Plane { glm::dvec3 n; double d; };
  auto row = [&](int i) { return glm::dvec3(vpm[0][i], vpm[1][i], vpm[2][i]); };
  const glm::dvec3 rx = row(0), ry = row(1), rw = row(3);
  const double tx = vpm[3][0], ty = vpm[3][1], tw = vpm[3][3];
  const Plane planes[11] = {
      {{1, 0, 0}, hi.x}, {{-1, 0, 0}, -lo.x}, {{0, 1, 0}, hi.y}, {{0, -1, 0}, -lo.y}, {{0, 0, 1}, hi.z},
      {{0, 0, -1}, -lo.z}, {-rw, tw - near_dist}, {rx - rw, tw - tx}, {-rx - rw, tw + tx}, {ry - rw, tw - ty},
      {-ry - rw, tw + ty}};
  std::vector<glm::dvec4> out;
  for (int i = 0; i < 11; ++i)
    for (int j = i + 1; j < 11; ++j)
      for (int k = j + 1; k < 11; ++k) {
        const glm::dmat3 m = glm::transpose(glm::dmat3(planes[i].n, planes[j].n, planes[k].n));
        const double det = glm::determinant(m);
        if (!(std::abs(det) > 1e-12 * glm::length(planes[i].n) * glm::length(planes[j].n) * glm::length(planes[k].n)))
          continue;
        const glm::dvec3 p = glm::inverse(m) * glm::dvec3(planes[i].d, planes[j].d, planes[k].d);
        bool inside = true;
        for (const Plane& q : planes)
          inside = inside && glm::dot(q.n, p) <= q.d + 1e-9 * (std::abs(q.d) + glm::length(q.n) * glm::length(p) + 1.0);
        if (!inside) continue;
        const glm::dvec4 clip = vpm * glm::dvec4(p, 1.0);
        if (clip.w > 0) out.push_back(clip);
      }
  return out;
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
  // In front of the near plane with room to spare: no clipping at the near plane on the GPU.
  // Otherwise the GPU clips the box there: its fragments come from the part of the box inside the
  // view volume, whose nearest point and screen rectangle are at its vertices. That box is padded
  // by at least as much as the query pads it (twice the larger of its two pads).
  const double pad2 = 2.0 * std::max(pad, 0.25 * 2.0 * std::tan(cam.fovy_rad * 0.5) / vp.height * glm::length(far));
  ClipBounds b = clip_bounds(plo, phi, vpm, cam.near_dist * (1.0 + 1e-3), lo - pad2, hi + pad2, cam.near_dist);
  if (b.empty()) return p;  // a query decides
  const double xmin = b.xmin, xmax = b.xmax, ymin = b.ymin, ymax = b.ymax, zmax = b.zmax, wmin = b.wmin;
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
