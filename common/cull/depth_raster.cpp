#include "common/cull/depth_raster.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <unordered_map>

#if defined(__x86_64__)
#include <immintrin.h>
#endif

#include <glm/gtc/matrix_transform.hpp>

namespace occ {

namespace {
constexpr double kSub = 256.0;               // sub-pixel steps per pixel (8 bits, as GL's)
constexpr double kMaxWindow = 1048576.0;     // 2^20 pixels: beyond it a triangle is left out
constexpr double kGuard = 262144.0;          // 2^18 pixels: triangles reaching beyond are clipped there
constexpr double kOffsetSlope = 0.1;         // SceneRenderer::kOccluderSlopeOffset, as the GL OR's offset
constexpr double kOffsetRelative = 1.0 / 1048576.0;
// GL computes depth in float: z = P22 z_eye + P32, then z / w; far off the two terms nearly
// cancel, so its error is a few ulps of P32 / w (near the far plane far more than an ulp of the
// depth), not of the depth. Here it is computed in double and moved back by this many such ulps.
constexpr double kDepthUlps = 8.0;
constexpr double kGuardBand = 8192;  // pixels: corners beyond are clipped by GL's own clipper
constexpr double kNearEdge = 2.0;            // sub-pixels: GL's snapping may differ by one at each end
constexpr double kOffLine = 1.0 / 16;         // pixels: an edge's triangles are not edge-on
// A tested depth is moved forward by two float ulps of itself (relative, not absolute: depths
// far off are small in reverse-Z, and an absolute bound such as 1e-7 would be a large part of them).
constexpr double kStoreUlps = 0x1p-22;
constexpr double kPadSubpixels = 4;  // BoxQuerier::kPadSubpixels (GL's query box, on screen)

// floor(a / b) and ceil(a / b) for b > 0.
int64_t floor_div(int64_t a, int64_t b) { return a >= 0 ? a / b : -((-a + b - 1) / b); }
int64_t ceil_div(int64_t a, int64_t b) { return -floor_div(-a, b); }

// The spans' scalar loops; the AVX2 versions compute the same values four at a time (no fused
// multiply-add: the same roundings).
void fill_scalar(float* row, int64_t n, double z0, double dz) {
  for (int64_t k = 0; k < n; ++k) {
    const float d = float(std::min(z0 + dz * double(k), 1.0));
    if (d > row[k]) row[k] = d;
  }
}
bool reaches_scalar(const float* row, int64_t n, double z0, double dz) {
  for (int64_t k = 0; k < n; ++k)
    if (float(z0 + dz * double(k)) >= row[k]) return true;
  return false;
}
#if defined(__x86_64__)
__attribute__((target("avx2"))) void fill_avx2(float* row, int64_t n, double z0, double dz) {
  const __m256d vz0 = _mm256_set1_pd(z0), vdz = _mm256_set1_pd(dz), one = _mm256_set1_pd(1.0),
                four = _mm256_set1_pd(4.0);
  __m256d k = _mm256_set_pd(3.0, 2.0, 1.0, 0.0);
  int64_t i = 0;
  for (; i + 4 <= n; i += 4, k = _mm256_add_pd(k, four)) {
    const __m128 d = _mm256_cvtpd_ps(_mm256_min_pd(_mm256_add_pd(vz0, _mm256_mul_pd(vdz, k)), one));
    _mm_storeu_ps(row + i, _mm_max_ps(d, _mm_loadu_ps(row + i)));
  }
  for (; i < n; ++i) {
    const float d = float(std::min(z0 + dz * double(i), 1.0));
    if (d > row[i]) row[i] = d;
  }
}
__attribute__((target("avx2"))) bool reaches_avx2(const float* row, int64_t n, double z0, double dz) {
  const __m256d vz0 = _mm256_set1_pd(z0), vdz = _mm256_set1_pd(dz), four = _mm256_set1_pd(4.0);
  __m256d k = _mm256_set_pd(3.0, 2.0, 1.0, 0.0);
  int64_t i = 0;
  for (; i + 4 <= n; i += 4, k = _mm256_add_pd(k, four)) {
    const __m128 d = _mm256_cvtpd_ps(_mm256_add_pd(vz0, _mm256_mul_pd(vdz, k)));
    if (_mm_movemask_ps(_mm_cmpge_ps(d, _mm_loadu_ps(row + i)))) return true;
  }
  for (; i < n; ++i)
    if (float(z0 + dz * double(i)) >= row[i]) return true;
  return false;
}
const bool kAvx2 = __builtin_cpu_supports("avx2");
#else
constexpr bool kAvx2 = false;
#endif
}  // namespace

namespace depth_span {
bool vector_available() { return kAvx2; }
void fill(float* row, int64_t n, double z0, double dz, bool vector) {
#if defined(__x86_64__)
  if (vector && kAvx2) return fill_avx2(row, n, z0, dz);
#endif
  fill_scalar(row, n, z0, dz);
}
bool reaches(const float* row, int64_t n, double z0, double dz, bool vector) {
#if defined(__x86_64__)
  if (vector && kAvx2) return reaches_avx2(row, n, z0, dz);
#endif
  return reaches_scalar(row, n, z0, dz);
}
}  // namespace depth_span

DepthRaster::DepthRaster(int width, int height)
    : width_(std::max(width, 1)),
      height_(std::max(height, 1)),
      depth_(size_t(width_) * size_t(height_), 0.0f) {}

void DepthRaster::set_projection(double p22, double p32) {
  error_ = kDepthUlps * 0x1p-24 * std::abs(p22);
  error_w_ = kDepthUlps * 0x1p-24 * std::abs(p32);
}

void DepthRaster::clear() {
  std::fill(depth_.begin(), depth_.end(), 0.0f);
}

DepthRaster::V DepthRaster::project(const glm::dvec4& p) const {
  const double r = 1.0 / p.w;  // within an ulp or two of dividing each: far below the margins
  return {(p.x * r * 0.5 + 0.5) * width_, (p.y * r * 0.5 + 0.5) * height_, p.z * r, p.w};
}

void DepthRaster::draw(const glm::dmat4& clip_from_object, std::span<const glm::vec3> positions,
                       std::span<const uint32_t> indices, Faces faces, std::span<const uint32_t> across) {
  run(clip_from_object, positions, indices, faces, false, across);
}

bool DepthRaster::shows(const glm::dmat4& clip_from_object, std::span<const glm::vec3> positions,
                        std::span<const uint32_t> indices, Faces faces, std::span<const uint32_t> across) {
  return run(clip_from_object, positions, indices, faces, true, across);
}

bool DepthRaster::query_shows(const glm::dmat4& clip_from_object, std::span<const glm::vec3> positions,
                              std::span<const uint32_t> indices) {
  as_query_ = true;
  const bool shown = run(clip_from_object, positions, indices, Faces::ccw, true, {});
  as_query_ = false;
  return shown;
}

bool DepthRaster::run(const glm::dmat4& clip_from_object, std::span<const glm::vec3> positions,
                      std::span<const uint32_t> indices, Faces faces, bool test, std::span<const uint32_t> across) {
  if (clip_.size() < positions.size()) {
    clip_.resize(positions.size());
    window_.resize(positions.size());
    stamp_.resize(positions.size(), 0);
  }
  if (++draw_ == 0) {  // the stamps wrapped: none is current
    std::fill(stamp_.begin(), stamp_.end(), 0);
    draw_ = 1;
  }
  // Vertex v in clip space, and (where not in front of the near plane) its window position.
  auto vertex = [&](uint32_t v) {
    if (stamp_[v] != draw_) {
      stamp_[v] = draw_;
      const glm::vec3& o = positions[v];
      const glm::dvec4 c = clip_from_object[0] * double(o.x) + clip_from_object[1] * double(o.y) +
                           clip_from_object[2] * double(o.z) + clip_from_object[3];
      clip_[v] = c;
      if (c.w - c.z >= 0 && c.w > 0) window_[v] = project(c);
    }
    return v;
  };
  auto in_front = [&](uint32_t v) { return !(clip_[v].w - clip_[v].z >= 0 && clip_[v].w > 0); };
  const bool adjacency = across.size() == indices.size();
  // A test visits every 8th triangle first, then the ones after them: neighbours in a mesh's
  // order lie close together, so one that shows is found sooner across the whole part.
  const size_t triangles = indices.size() / 3, stride = test ? 8 : 1, rows = triangles / stride + 1;
  for (size_t n = 0; n < rows * stride; ++n) {
    const size_t k = stride == 1 ? n : (n % rows) * stride + n / rows;  // a permutation of 0 .. rows * stride
    if (k >= triangles) continue;
    const size_t t = 3 * k;
    const uint32_t i[3] = {indices[t], indices[t + 1], indices[t + 2]};
    if (i[0] >= positions.size() || i[1] >= positions.size() || i[2] >= positions.size()) continue;
    for (uint32_t v : i) vertex(v);
    // Which edges are outlines on screen: not where the triangle across (same mesh, drawn in the
    // same call, facing as this one is drawn) lies on the other side of it (the two cover
    // both sides, in GL too: a centre near that edge is covered by one of them either way).
    uint8_t outline = 7;
    const bool whole = !in_front(i[0]) && !in_front(i[1]) && !in_front(i[2]);
    if (whole) {
      // Most triangles of a detailed mesh cover no pixel centre, or face away: done with them
      // here. A test widens the box by its margin (and more: what GL's snapping may add).
      const V &p = window_[i[0]], &q = window_[i[1]], &r = window_[i[2]];
      if (!test && faces != Faces::both) {  // facing away: the cheapest test first
        const double area = (q.x - p.x) * (r.y - p.y) - (r.x - p.x) * (q.y - p.y);
        const double edge_on = 4.0 / (kSub * kSub);  // well clear of what snapping may flip
        if ((faces == Faces::ccw && area < -edge_on) || (faces == Faces::cw && area > edge_on)) continue;
      }
      const double grow = test ? (kNearEdge + 2.0) / kSub : 0.0;
      const double x0 = std::min({p.x, q.x, r.x}) - grow, x1 = std::max({p.x, q.x, r.x}) + grow;
      const double y0 = std::min({p.y, q.y, r.y}) - grow, y1 = std::max({p.y, q.y, r.y}) + grow;
      if (x1 < 0.5 || y1 < 0.5 || x0 > width_ - 0.5 || y0 > height_ - 0.5) continue;
      // No pixel centre (k + 0.5) within [x0, x1] or [y0, y1]: only a box narrower than a pixel
      // can miss them all, so the rounding is done for those only.
      if ((x1 - x0 < 1.0 && std::ceil(x0 - 0.5) > std::floor(x1 - 0.5)) ||
          (y1 - y0 < 1.0 && std::ceil(y0 - 0.5) > std::floor(y1 - 0.5)))
        continue;  // (draw: leaving one out only makes HC prove less)
    }
    if (adjacency) {
      for (int k = 0; k < 3; ++k) {
        const uint32_t a = across[t + size_t(k)];
        if (a == kNone) continue;
        const uint32_t o = a & ~kReversed;
        if (o >= positions.size()) continue;
        vertex(o);
        bool other_side = false;
        if (whole && !in_front(o)) {
          const V &p = window_[i[k]], &q = window_[i[(k + 1) % 3]], &r = window_[i[(k + 2) % 3]], &w = window_[o];
          const double er = (q.x - p.x) * (r.y - p.y) - (q.y - p.y) * (r.x - p.x);
          const double ew = (q.x - p.x) * (w.y - p.y) - (q.y - p.y) * (w.x - p.x);
          // Both well off the line (1/16 pixel): neither triangle is edge-on to either
          // rasteriser, whose snapping would otherwise decide whether it covers anything.
          // |e| > off compared squared (off = kOffLine |q - p|: no square root per edge).
          const double off2 = kOffLine * kOffLine * ((q.x - p.x) * (q.x - p.x) + (q.y - p.y) * (q.y - p.y));
          const bool opposite = (er > 0 && ew < 0) || (er < 0 && ew > 0);
          other_side = opposite && er * er > off2 && ew * ew > off2;
        } else {
          // A corner in front of the near plane (the edge is clipped): the sides of the plane
          // through the eye and the edge, in clip space (x, y, w), where the visible parts of
          // the two triangles next to the edge lie; well off it (a thousandth of a radian).
          const glm::dvec3 p(clip_[i[k]].x, clip_[i[k]].y, clip_[i[k]].w), q(clip_[i[(k + 1) % 3]].x,
                                                                               clip_[i[(k + 1) % 3]].y,
                                                                               clip_[i[(k + 1) % 3]].w);
          const glm::dvec3 r(clip_[i[(k + 2) % 3]].x, clip_[i[(k + 2) % 3]].y, clip_[i[(k + 2) % 3]].w);
          const glm::dvec3 w(clip_[o].x, clip_[o].y, clip_[o].w);
          const glm::dvec3 n = glm::cross(p, q);
          const double dr = glm::dot(n, r), dw = glm::dot(n, w), ln = glm::length(n);
          const double off_r = 1e-3 * ln * glm::length(r), off_w = 1e-3 * ln * glm::length(w);
          other_side = (dr > off_r && dw < -off_w) || (dr < -off_r && dw > off_w);
        }
        if (other_side && (faces == Faces::both || (a & kReversed))) outline &= uint8_t(~(1u << k));
      }
    }
    if (clip_and_draw(clip_[i[0]], clip_[i[1]], clip_[i[2]], faces, test, outline)) return true;
  }
  return false;
}

std::vector<uint32_t> DepthRaster::adjacency(std::span<const glm::vec3> positions, std::span<const uint32_t> indices) {
  // Corners welded by position (bit for bit): meshes split at normals or texture seams still join.
  // Only the vertices these indices use, in ascending order (a cluster of a mesh of millions of
  // vertices costs its own size): verts[k] has the weld id ids[k].
  std::vector<uint32_t> verts;
  verts.reserve(indices.size());
  for (uint32_t v : indices)
    if (v < positions.size()) verts.push_back(v);
  std::sort(verts.begin(), verts.end());
  verts.erase(std::unique(verts.begin(), verts.end()), verts.end());
  std::unordered_map<uint64_t, uint32_t> weld;
  std::vector<uint32_t> ids(verts.size());
  for (size_t k = 0; k < verts.size(); ++k) {
    const uint32_t v = verts[k];
    uint32_t b[3];
    std::memcpy(b, &positions[v], sizeof b);
    const uint64_t h = (uint64_t(b[0]) * 0x9E3779B97F4A7C15ull) ^ (uint64_t(b[1]) * 0xC2B2AE3D27D4EB4Full) ^
                       (uint64_t(b[2]) * 0x165667B19E3779F9ull);
    // Collisions of the hash are told apart by position below (a collision only loses adjacency).
    ids[k] = weld.emplace(h, v).first->second;
    if (positions[ids[k]] != positions[v]) ids[k] = v;
  }
  const auto id_of = [&](uint32_t v) { return ids[size_t(std::lower_bound(verts.begin(), verts.end(), v) - verts.begin())]; };
  // Each undirected edge (welded) -> the first corner starting it and how many do; an edge of
  // exactly two triangles joins them.
  struct Seen {
    uint32_t corner = 0, count = 0;
  };
  std::unordered_map<uint64_t, Seen> edges;
  const size_t n = indices.size() / 3 * 3;
  auto next = [](size_t c) { return c - c % 3 + (c + 1) % 3; };
  auto key = [&](uint32_t a, uint32_t b) { return a < b ? uint64_t(a) << 32 | b : uint64_t(b) << 32 | a; };
  auto valid = [&](size_t c) { return indices[c] < positions.size() && indices[next(c)] < positions.size(); };
  for (size_t c = 0; c < n; ++c) {
    if (!valid(c)) continue;
    Seen& e = edges[key(id_of(indices[c]), id_of(indices[next(c)]))];
    if (e.count++ == 0) e.corner = uint32_t(c);
  }
  std::vector<uint32_t> across(n, kNone);
  for (size_t c = 0; c < n; ++c) {
    if (!valid(c)) continue;
    const Seen& e = edges[key(id_of(indices[c]), id_of(indices[next(c)]))];
    if (e.count != 2 || e.corner == c) continue;
    const size_t oc = e.corner;
    // Consistent winding: the other triangle runs the edge the other way.
    const uint32_t reversed = id_of(indices[oc]) == id_of(indices[next(c)]) ? kReversed : 0u;
    across[c] = indices[next(next(oc))] | reversed;
    across[oc] = indices[next(next(c))] | reversed;
  }
  return across;
}

// Clips away what lies in front of the near plane (reverse-Z: z > w there, behind the eye too);
// draws the rest, or with `test` tests it (whether it shows anywhere in front of the depth).
bool DepthRaster::clip_and_draw(const glm::dvec4& a, const glm::dvec4& b, const glm::dvec4& c, Faces faces, bool test,
                                uint8_t outline) {
  const glm::dvec4* in[3] = {&a, &b, &c};
  const double s[3] = {a.w - a.z, b.w - b.z, c.w - c.z};  // >= 0: not in front of the near plane
  const int inside = (s[0] >= 0) + (s[1] >= 0) + (s[2] >= 0);
  if (inside == 0) return false;
  // Off screen on one side (all three beyond the same clip plane): nothing to draw.
  if ((a.x > a.w && b.x > b.w && c.x > c.w) || (a.x < -a.w && b.x < -b.w && c.x < -c.w) ||
      (a.y > a.w && b.y > b.w && c.y > c.w) || (a.y < -a.w && b.y < -b.w && c.y < -c.w) ||
      (a.z < 0 && b.z < 0 && c.z < 0))
    return false;
  auto tri = [&](const V& p, const V& q, const V& r, uint8_t edges) {
    if (test) return test_triangle(p, q, r, faces, edges);
    triangle(p, q, r, faces, edges);
    return false;
  };
  // Within the guard band (window coordinates well under kMaxWindow) and not in front of the near
  // plane: as it is. Else clipped to both.
  const double gx = kGuard / double(width_), gy = kGuard / double(height_);
  auto in_band = [&](const glm::dvec4& v) { return std::abs(v.x) <= gx * v.w && std::abs(v.y) <= gy * v.w; };
  if (inside == 3 && in_band(a) && in_band(b) && in_band(c)) return tri(project(a), project(b), project(c), outline);
  // Sutherland-Hodgman against the near plane and the guard band's four, in order (the winding
  // is kept). Each corner of the polygon remembers the triangle's edges it lies on (bit k: edge
  // k, corner k to k + 1), so that its sides along them keep their outline bits; a side along a
  // clipping plane is an outline (the guard band's lie far off screen).
  struct Corner {
    glm::dvec4 v;
    uint8_t on;
  };
  Corner poly[8], next[8];
  int n = 0;
  for (int k = 0; k < 3; ++k) poly[n++] = {*in[k], uint8_t(1u << k | 1u << ((k + 2) % 3))};
  auto clip = [&](auto dist) {
    int m = 0;
    for (int k = 0; k < n; ++k) {
      const Corner &p = poly[k], &q = poly[(k + 1) % n];
      const double dp = dist(p.v), dq = dist(q.v);
      if (dp >= 0) next[m++] = p;
      if ((dp >= 0) != (dq >= 0)) next[m++] = {p.v + dp / (dp - dq) * (q.v - p.v), uint8_t(p.on & q.on)};
    }
    n = m;
    std::copy(next, next + m, poly);
  };
  clip([](const glm::dvec4& v) { return v.w - v.z; });
  clip([&](const glm::dvec4& v) { return gx * v.w - v.x; });
  clip([&](const glm::dvec4& v) { return gx * v.w + v.x; });
  clip([&](const glm::dvec4& v) { return gy * v.w - v.y; });
  clip([&](const glm::dvec4& v) { return gy * v.w + v.y; });
  if (n < 3) return false;
  for (int k = 0; k < n; ++k)
    if (!(poly[k].v.w > 0)) return test;  // a test cannot tell: it shows
  // The outline bit of polygon side a -> b: the triangle's edge both lie on, else a clipping plane's.
  auto side = [&](int a, int b) -> bool {
    const uint8_t both = poly[a].on & poly[b].on;
    return both ? (outline & both) != 0 : true;
  };
  const V p0 = project(poly[0].v);
  for (int k = 1; k + 1 < n; ++k) {
    // The fan's triangle (0, k, k + 1): its edges 0 -> k and k + 1 -> 0 are diagonals inside the
    // polygon (no outline) unless they are its sides.
    const uint8_t fan =
        uint8_t((k == 1 ? side(0, 1) : 0) | side(k, k + 1) << 1 | (k + 2 == n ? side(n - 1, 0) : 0) << 2);
    if (tri(p0, project(poly[k].v), project(poly[k + 1].v), fan)) return true;
  }
  return false;
}

// A triangle set up for rasterising: pixels px0..px1 x py0..py1 (its snapped bounding box on
// the viewport), edge values at (px0, py0) and their steps, and the depth plane.
struct DepthRaster::Setup {
  int64_t px0, px1, py0, py1;
  // Edge k from corner k to corner k+1: E(P) = (Q - P0) x (P - P0) >= 0 inside. A centre on an
  // edge belongs to it where the edge is a left (going down) or top (going left) one, so that
  // of two triangles sharing an edge exactly one covers it. T[k]: E under it is within the
  // rounding margin of the edge: drawn, such a centre is left out; tested, one outside the
  // triangle by less counts.
  int64_t A[3], B[3], E[3], T[3];  // E at (px0, py0); per pixel +A in x, +B in y
  double dzdx, dzdy, z00;          // the plane's depth at (px0, py0)'s centre, unmoved
  double back;                     // how far the plane is moved (back to draw, forward to test)
  bool degenerate = false;         // test only: no area after snapping (its box is tested)
  double zmax = 0, wmin = 1;
};

bool DepthRaster::setup(const V& a0, const V& b0, const V& c0, Faces faces, bool test, uint8_t outline,
                        Setup& s) const {
  for (const V* v : {&a0, &b0, &c0})
    if (!(std::abs(v->x) < kMaxWindow && std::abs(v->y) < kMaxWindow) || !std::isfinite(v->z)) {
      if (!test) return false;  // left out: fewer occluders
      // Tested: may show anywhere.
      s = Setup{};
      s.px0 = s.py0 = 0;
      s.px1 = width_ - 1;
      s.py1 = height_ - 1;
      s.degenerate = true;
      s.zmax = 1.0;
      s.wmin = 1e30;
      return true;
    }
  // Snapped to 1/256 pixel: the coverage test is exact integer arithmetic on these.
  auto fx = [](double x) {  // round to nearest (|x| < 2^20: no overflow)
    const double t = x * kSub;
    return int64_t(t >= 0 ? t + 0.5 : t - 0.5);
  };
  int64_t X[3] = {fx(a0.x), fx(b0.x), fx(c0.x)}, Y[3] = {fx(a0.y), fx(b0.y), fx(c0.y)};
  const V* v[3] = {&a0, &b0, &c0};
  const int64_t area = (X[1] - X[0]) * (Y[2] - Y[0]) - (X[2] - X[0]) * (Y[1] - Y[0]);
  // GL's snapping may give an edge-on triangle the other sign (or none): a test keeps it.
  const bool edge_on = std::abs(area) <= 4 * kSub * kSub / 256;
  if (!(test && edge_on) && ((faces == Faces::ccw && area < 0) || (faces == Faces::cw && area > 0))) return false;
  if (area < 0) {  // counter-clockwise from here on: edges 0 -> 2, 2 -> 1, 1 -> 0
    std::swap(X[1], X[2]);
    std::swap(Y[1], Y[2]);
    std::swap(v[1], v[2]);
    outline = uint8_t((outline & 1) << 2 | (outline & 2) | (outline & 4) >> 2);
  }
  const int64_t half = int64_t(kSub) / 2, sub = int64_t(kSub);
  // A centre closer to an edge than `near` sub-pixels may lie on its other side in GL (its own
  // rounding). Far from the viewport coordinates carry more rounding (clipped corners): the
  // margin grows with them.
  double extent = 0;
  for (const V* p : v) extent = std::max({extent, std::abs(p->x), std::abs(p->y)});
  const double near = kNearEdge + extent * kSub * 0x1p-21;
  // A test covers the pixels within the margin around the triangle too.
  const int64_t grow = test ? int64_t(std::ceil(near)) : 0;
  const int64_t minX = std::min({X[0], X[1], X[2]}) - grow, maxX = std::max({X[0], X[1], X[2]}) + grow;
  const int64_t minY = std::min({Y[0], Y[1], Y[2]}) - grow, maxY = std::max({Y[0], Y[1], Y[2]}) + grow;
  s.px0 = std::max<int64_t>(0, ceil_div(minX - half, sub));
  s.px1 = std::min<int64_t>(width_ - 1, floor_div(maxX - half, sub));
  s.py0 = std::max<int64_t>(0, ceil_div(minY - half, sub));
  s.py1 = std::min<int64_t>(height_ - 1, floor_div(maxY - half, sub));
  if (s.px0 > s.px1 || s.py0 > s.py1) return false;
  s.zmax = std::max({v[0]->z, v[1]->z, v[2]->z});
  s.wmin = std::min({v[0]->w, v[1]->w, v[2]->w});
  // The depth plane over window positions, from the unsnapped corners.
  const double ux = v[1]->x - v[0]->x, uy = v[1]->y - v[0]->y, uz = v[1]->z - v[0]->z;
  const double wx = v[2]->x - v[0]->x, wy = v[2]->y - v[0]->y, wz = v[2]->z - v[0]->z;
  const double det = ux * wy - wx * uy;
  if (area == 0 || edge_on || !(std::abs(det) > 1e-12)) {
    if (!test) return false;
    s.degenerate = true;  // its snapped box, at its nearest corner
    return true;
  }
  s.dzdx = (uz * wy - wz * uy) / det;
  s.dzdy = (ux * wz - wx * uz) / det;
  // GL sets up the plane in float from its corners: its error grows with the slopes times the
  // window coordinates (on screen and a guard band beyond).
  const double reach = std::min(extent, double(kGuardBand)) + double(width_) + double(height_);
  // The GL OR's offset, except for a box tested as GL's query of it would be (as_query()).
  const double offset =
      test && as_query_ ? 0.0 : kOffsetSlope * std::max(std::abs(s.dzdx), std::abs(s.dzdy)) + kOffsetRelative * std::abs(s.zmax);
  s.back = offset + error_w_ / s.wmin + error_ +
           kDepthUlps * 0x1p-24 * (std::abs(s.zmax) + (std::abs(s.dzdx) + std::abs(s.dzdy)) * reach);
  s.z00 = v[0]->z + s.dzdx * (double(s.px0) + 0.5 - v[0]->x) + s.dzdy * (double(s.py0) + 0.5 - v[0]->y);
  for (int k = 0; k < 3; ++k) {
    const int j = (k + 1) % 3;
    const int64_t dx = X[j] - X[k], dy = Y[j] - Y[k];
    const bool owns = dy < 0 || (dy == 0 && dx < 0);
    s.A[k] = -dy * sub;
    s.B[k] = dx * sub;
    s.E[k] = dx * (s.py0 * sub + half - Y[k]) - dy * (s.px0 * sub + half - X[k]) - (owns ? 0 : 1);
    // Inside an outline the triangle across covers what this one may not (GL likewise).
    s.T[k] = outline & (1u << k) ? int64_t(near * std::sqrt(double(dx) * double(dx) + double(dy) * double(dy))) + 1 : 0;
  }
  return true;
}

// The pixels of row `py` where every edge's E(px) = E + A (px - px0) >= above[k].
void DepthRaster::span(const Setup& s, const int64_t* E, const int64_t* above, int64_t& lo, int64_t& hi) {
  lo = s.px0;
  hi = s.px1;
  for (int k = 0; k < 3 && lo <= hi; ++k) {
    const int64_t e = E[k] - above[k];
    if (s.A[k] > 0)
      lo = std::max(lo, s.px0 + ceil_div(-e, s.A[k]));
    else if (s.A[k] < 0)
      hi = std::min(hi, s.px0 + floor_div(e, -s.A[k]));
    else if (e < 0)
      hi = lo - 1;
  }
}

void DepthRaster::triangle(const V& a0, const V& b0, const V& c0, Faces faces, uint8_t outline) {
  Setup s;
  if (!setup(a0, b0, c0, faces, false, outline, s)) return;
  const double dzdx = s.dzdx, z00 = s.z00 - s.back;  // moved back
  int64_t E[3] = {s.E[0], s.E[1], s.E[2]};
  if (s.px1 - s.px0 < 16) {
    // Narrow: each pixel's centre tested (the sign bits of the edge values, less their margins,
    // or'ed: a centre within the margin of an outline edge is left out).
    for (int64_t py = s.py0; py <= s.py1; ++py) {
      float* row = depth_.data() + size_t(py) * size_t(width_);
      int64_t e0 = E[0] - s.T[0], e1 = E[1] - s.T[1], e2 = E[2] - s.T[2];
      double z = z00 + s.dzdy * double(py - s.py0);
      for (int64_t px = s.px0; px <= s.px1; ++px, z += dzdx) {
        if ((e0 | e1 | e2) >= 0) {
          const float d = float(std::min(z, 1.0));
          if (d > row[px]) row[px] = d;
        }
        e0 += s.A[0];
        e1 += s.A[1];
        e2 += s.A[2];
      }
      for (int k = 0; k < 3; ++k) E[k] += s.B[k];
    }
    return;
  }
  for (int64_t py = s.py0; py <= s.py1; ++py) {
    // Wide: the row's span of centres clear of every outline edge's margin.
    int64_t lo, hi;
    span(s, E, s.T, lo, hi);
    if (lo <= hi)
      depth_span::fill(depth_.data() + size_t(py) * size_t(width_) + size_t(lo), hi - lo + 1,
                       z00 + s.dzdy * double(py - s.py0) + dzdx * double(lo - s.px0), dzdx);
    for (int k = 0; k < 3; ++k) E[k] += s.B[k];
  }
}

bool DepthRaster::test_triangle(const V& a0, const V& b0, const V& c0, Faces faces, uint8_t outline) const {
  Setup s;
  if (!setup(a0, b0, c0, faces, true, outline, s)) return false;
  if (s.degenerate) {  // its snapped box at its nearest corner, moved forward
    const float d = float(s.zmax + kOffsetRelative * std::abs(s.zmax) + error_w_ / std::max(s.wmin, 1e-30) + error_ +
                          kStoreUlps * std::abs(s.zmax));
    for (int64_t py = s.py0; py <= s.py1; ++py)
      for (int64_t px = s.px0; px <= s.px1; ++px)
        if (d >= depth_[size_t(py) * size_t(width_) + size_t(px)]) return true;
    return false;
  }
  // Pixels within the margin of an edge count (GL may cover them), at the plane moved forward
  // (and by the float rounding of the depths compared).
  const int64_t below[3] = {-s.T[0], -s.T[1], -s.T[2]};
  const double z00 = s.z00 + s.back + kStoreUlps * std::abs(s.zmax);
  int64_t E[3] = {s.E[0], s.E[1], s.E[2]};
  for (int64_t py = s.py0; py <= s.py1; ++py) {
    int64_t lo, hi;
    span(s, E, below, lo, hi);
    if (lo <= hi && depth_span::reaches(depth_.data() + size_t(py) * size_t(width_) + size_t(lo), hi - lo + 1,
                                        z00 + s.dzdy * double(py - s.py0) + s.dzdx * double(lo - s.px0), s.dzdx))
      return true;
    for (int k = 0; k < 3; ++k) E[k] += s.B[k];
  }
  return false;
}

std::optional<CpuOccluders> CpuOccluders::copy(const Scene& scene, const Hierarchy& h, int width, int height,
                                               std::string* why) {
  if (scene.mapped || scene.geometry_released()) {
    if (why) *why = "the scene's arrays are not in memory (read from the scene cache within the geometry budget)";
    return std::nullopt;
  }
  CpuOccluders c(h, width, height);
  c.meshes_.resize(scene.meshes.size());
  std::vector<uint8_t> used(scene.meshes.size(), 0);
  c.items_.resize(h.items().size());
  for (size_t i = 0; i < h.items().size(); ++i) {
    const Item& it = h.items()[i];
    const Object& o = scene.objects[it.object];
    const Mesh& m = scene.meshes[o.mesh];
    const Material* mat = scene.material_of(o.mesh);
    ItemRef& r = c.items_[i];
    r.occludes = (!mat || mat->alpha_mode == AlphaMode::Opaque) && it.cluster < m.clusters.size();
    if (!r.occludes) continue;
    const bool mirrored = glm::determinant(glm::dmat3(o.transform)) < 0.0;
    r.faces = !mat || mat->double_sided ? DepthRaster::Faces::both
              : mirrored               ? DepthRaster::Faces::cw
                                       : DepthRaster::Faces::ccw;
    r.mesh = o.mesh;
    r.first_index = m.clusters[it.cluster].first_index;
    r.index_count = m.clusters[it.cluster].index_count;
    r.transform = o.transform;
    used[o.mesh] = 1;
  }
  for (size_t m = 0; m < scene.meshes.size(); ++m)
    if (used[m]) {
      const Mesh& mesh = scene.meshes[m];
      MeshCopy& mc = c.meshes_[m];
      mc.positions = mesh.positions;
      mc.indices = mesh.indices;
      mc.across.assign(mesh.indices.size(), DepthRaster::kNone);
      for (const MeshCluster& cl : mesh.clusters) {  // within a cluster: what one draw holds
        if (size_t(cl.first_index) + cl.index_count > mesh.indices.size()) continue;
        const std::vector<uint32_t> a = DepthRaster::adjacency(
            mesh.positions, std::span<const uint32_t>(mesh.indices).subspan(cl.first_index, cl.index_count));
        std::copy(a.begin(), a.end(), mc.across.begin() + cl.first_index);
      }
    }
  return c;
}

uint64_t CpuOccluders::bytes() const {
  uint64_t b = items_.capacity() * sizeof(ItemRef);
  for (const MeshCopy& m : meshes_)
    b += m.positions.capacity() * sizeof(glm::vec3) + m.indices.capacity() * 4 + m.across.capacity() * 4;
  return b;
}

void CpuOccluders::begin(const Camera& cam) {
  raster_.clear();
  // Camera-relative, as the GL renderer's model-view: the translation is taken in double.
  const glm::dmat4 proj = cam.projection();
  raster_.set_projection(proj[2][2], proj[3][2]);
  clip_from_world_ = proj * cam.view_rotation() * glm::translate(glm::dmat4(1.0), -cam.eye);
  eye_ = cam.eye;
  sections_ = cam.sections;
  pixel_per_distance_ = 2.0 * std::tan(cam.fovy_rad * 0.5) / double(raster_.height());
  // The eye to the near rectangle's corners, with slack (as BoxQuerier's).
  const double ty = std::tan(cam.fovy_rad * 0.5), tx = ty * cam.aspect;
  near_reach_ = cam.near_dist * std::sqrt(1.0 + tx * tx + ty * ty) * (1.0 + 1e-3);
}

void CpuOccluders::draw_leaf(uint32_t node, uint32_t level) {
  const HNode& n = h_->node(node);
  if (level != 0 || !n.leaf()) return;
  for (uint32_t i = n.first_item; i < n.first_item + n.item_count; ++i) {
    const ItemRef& r = items_[i];
    if (!r.occludes) continue;
    // An item a section plane cuts is left out whole: GL draws less of it, never more.
    if (!sections_.empty() && !sections_.keeps_all(h_->items()[i].box, eye_)) continue;
    const MeshCopy& m = meshes_[r.mesh];
    if (size_t(r.first_index) + r.index_count > m.indices.size()) continue;
    raster_.draw(clip_from_world_ * r.transform, m.positions,
                 std::span<const uint32_t>(m.indices).subspan(r.first_index, r.index_count), r.faces,
                 std::span<const uint32_t>(m.across).subspan(r.first_index, r.index_count));
  }
}

bool CpuOccluders::leaf_shows(uint32_t node) {
  const HNode& n = h_->node(node);
  if (!n.leaf()) return true;
  for (uint32_t i = n.first_item; i < n.first_item + n.item_count; ++i)
    if (!items_[i].occludes) return true;  // MASK, BLEND: not on the CPU
  for (uint32_t i = n.first_item; i < n.first_item + n.item_count; ++i) {
    const ItemRef& r = items_[i];
    const MeshCopy& m = meshes_[r.mesh];
    if (size_t(r.first_index) + r.index_count > m.indices.size()) return true;
    if (raster_.shows(clip_from_world_ * r.transform, m.positions,
                      std::span<const uint32_t>(m.indices).subspan(r.first_index, r.index_count), r.faces,
                      std::span<const uint32_t>(m.across).subspan(r.first_index, r.index_count)))
      return true;
  }
  return false;
}

bool CpuOccluders::box_shows(const Aabb& box, double relative_pad) {
  // Corners relative to the box's centre (small floats), the centre in the transform (double).
  const glm::dvec3 c = 0.5 * (box.min + box.max), half = 0.5 * (box.max - box.min);
  const glm::dvec3 far = glm::abs(c - eye_) + half;
  // As GL's query box (BoxQuerier): also at least kPadSubpixels steps of GL's 1/256 pixel grid
  // on screen, at the farthest corner's distance.
  const double pad = std::max(relative_pad * std::max({far.x, far.y, far.z}),
                              kPadSubpixels / kSub * pixel_per_distance_ * glm::length(far));
  // Rounded outward to float, and a float ulp more.
  const glm::dvec3 e = half + pad + 1e-6 * (glm::abs(half) + pad);
  glm::vec3 corners[8];
  for (int i = 0; i < 8; ++i)
    corners[i] = glm::vec3(float((i & 1) ? e.x : -e.x), float((i & 2) ? e.y : -e.y), float((i & 4) ? e.z : -e.z));
  // The six faces, two triangles each, counter-clockwise seen from outside (corner i: bit 0 x,
  // bit 1 y, bit 2 z): the front faces, as GL's query draws them.
  static constexpr uint32_t kFaces[36] = {0, 2, 3, 0, 3, 1, 4, 5, 7, 4, 7, 6, 0, 1, 5, 0, 5, 4,
                                          2, 6, 7, 2, 7, 3, 0, 4, 6, 0, 6, 2, 1, 3, 7, 1, 7, 5};
  // The padded box within reach of the near rectangle (the eye may be inside it, the near plane
  // may cut away its front faces where what it holds lies beyond the plane): it shows, as GL's
  // query counts it (BoxQuerier).
  const glm::dvec3 gap = glm::max(glm::max(-(c - eye_) - e, (c - eye_) - e), glm::dvec3(0.0));
  if (glm::dot(gap, gap) <= near_reach_ * near_reach_) return true;
  return raster_.query_shows(clip_from_world_ * glm::translate(glm::dmat4(1.0), c), corners, kFaces);
}

}  // namespace occ
