#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <vector>

#include "common/cull/depth_raster.hpp"
#include "random_util.hpp"

using namespace occ;

namespace {
// Identity clip space: window x = (x / w * 0.5 + 0.5) * width, depth = z / w.
const glm::dmat4 kIdentity(1.0);

glm::vec3 ndc(double px, double py, double z, int w, int h) {  // window position -> NDC
  return {float(px / w * 2.0 - 1.0), float(py / h * 2.0 - 1.0), float(z)};
}

float at(const DepthRaster& r, int x, int y) { return r.depth()[size_t(y) * size_t(r.width()) + size_t(x)]; }

// Which side of edge a -> b the point p lies on, in pixels (positive: left of it).
double side(glm::dvec2 a, glm::dvec2 b, glm::dvec2 p) {
  const glm::dvec2 e = b - a;
  return (e.x * (p.y - a.y) - e.y * (p.x - a.x)) / std::sqrt(e.x * e.x + e.y * e.y);
}
}  // namespace

// A grid of quads with jittered inner corners over the whole viewport leaves no pixel uncovered:
// triangles sharing an edge (adjacency) are watertight, their centres near it not left out.
TEST(DepthRaster, SharedEdgesLeaveNoHoles) {
  occtest::Lcg rnd{7};
  const int w = 97, h = 61, n = 9;
  std::vector<glm::vec3> p;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) {
      const bool inner = i > 0 && i < n && j > 0 && j < n;
      const double x = -2.0 + 4.0 * i / n + (inner ? 0.3 * (rnd() - 0.5) : 0.0);  // beyond the viewport
      const double y = -2.0 + 4.0 * j / n + (inner ? 0.3 * (rnd() - 0.5) : 0.0);
      p.push_back({float(x), float(y), float(0.3 + 0.4 * rnd())});
    }
  std::vector<uint32_t> idx;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const uint32_t a = uint32_t(j * (n + 1) + i), b = a + 1, c = a + uint32_t(n + 1), d = c + 1;
      idx.insert(idx.end(), {a, b, d, a, d, c});
    }
  DepthRaster r(w, h);
  r.draw(kIdentity, p, idx, DepthRaster::Faces::both, DepthRaster::adjacency(p, idx));
  int holes = 0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) holes += at(r, x, y) <= 0.0f;
  EXPECT_EQ(holes, 0);
}

// Random triangles: a pixel whose centre lies inside by more than 1/64 pixel is covered (by
// less, GL might not cover it: left out), one outside is not, and a covered pixel's depth lies a little behind the
// triangle's plane (never in front of it: reverse-Z, smaller is farther).
TEST(DepthRaster, CoversCentresInsideAndDrawsBehindThePlane) {
  occtest::Lcg rnd{11};
  const int w = 64, h = 48;
  for (int t = 0; t < 200; ++t) {
    glm::dvec2 c[3];
    double z[3];
    for (int k = 0; k < 3; ++k) {
      c[k] = {-8 + (w + 16) * rnd(), -8 + (h + 16) * rnd()};
      z[k] = 0.05 + 0.9 * rnd();
    }
    DepthRaster r(w, h);
    const std::vector<glm::vec3> p = {ndc(c[0].x, c[0].y, z[0], w, h), ndc(c[1].x, c[1].y, z[1], w, h),
                                      ndc(c[2].x, c[2].y, z[2], w, h)};
    const std::vector<uint32_t> idx = {0, 1, 2};
    r.draw(kIdentity, p, idx, DepthRaster::Faces::both);
    const double area = (c[1].x - c[0].x) * (c[2].y - c[0].y) - (c[2].x - c[0].x) * (c[1].y - c[0].y);
    if (std::abs(area) < 1.0) continue;
    const double sgn = area > 0 ? 1 : -1;
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const glm::dvec2 q{x + 0.5, y + 0.5};
        const double d = std::min({sgn * side(c[0], c[1], q), sgn * side(c[1], c[2], q), sgn * side(c[2], c[0], q)});
        const float got = at(r, x, y);
        // The plane's depth at the centre (barycentric) and its slopes per pixel: the draw moves
        // it back by 0.2 of the larger slope (a sliver may go behind the far plane)...
        const double l1 = ((q.x - c[0].x) * (c[2].y - c[0].y) - (c[2].x - c[0].x) * (q.y - c[0].y)) / area;
        const double l2 = ((c[1].x - c[0].x) * (q.y - c[0].y) - (q.x - c[0].x) * (c[1].y - c[0].y)) / area;
        const double plane = z[0] + l1 * (z[1] - z[0]) + l2 * (z[2] - z[0]);
        const double dzdx = ((z[1] - z[0]) * (c[2].y - c[0].y) - (z[2] - z[0]) * (c[1].y - c[0].y)) / area;
        const double dzdy = ((c[1].x - c[0].x) * (z[2] - z[0]) - (c[2].x - c[0].x) * (z[1] - z[0])) / area;
        // ...and by GL's rounding allowance: 8 float ulps of the slopes times the corners' reach.
        double extent = 0;
        for (const glm::dvec2& k : c) extent = std::max({extent, std::abs(k.x), std::abs(k.y)});
        const double back = 0.2 * std::max(std::abs(dzdx), std::abs(dzdy)) +
                            8 * 0x1p-24 * (std::abs(dzdx) + std::abs(dzdy)) * (extent + w + h) + 1e-4;
        if (d > 1.0 / 64 && plane - back > 1e-6) {
          ASSERT_GT(got, 0.0f) << "triangle " << t << " pixel " << x << "," << y;
          EXPECT_LE(got, plane) << "in front of its plane: triangle " << t << " pixel " << x << "," << y;
          EXPECT_GT(got, plane - back) << "far behind its plane: triangle " << t;
        } else if (d < 0) {
          ASSERT_EQ(got, 0.0f) << "triangle " << t << " pixel " << x << "," << y;
        }
      }
  }
}

// Single-sided: counter-clockwise faces are drawn with Faces::ccw, clockwise ones with cw.
TEST(DepthRaster, CullsTheFacesGlWould) {
  const int w = 16, h = 16;
  const std::vector<glm::vec3> p = {ndc(2, 2, 0.5, w, h), ndc(14, 2, 0.5, w, h), ndc(2, 14, 0.5, w, h)};
  const std::vector<uint32_t> ccw = {0, 1, 2}, cw = {0, 2, 1};
  for (auto [idx, faces, drawn] : {std::tuple{ccw, DepthRaster::Faces::ccw, true}, {ccw, DepthRaster::Faces::cw, false},
                                   {cw, DepthRaster::Faces::ccw, false}, {cw, DepthRaster::Faces::cw, true},
                                   {cw, DepthRaster::Faces::both, true}}) {
    DepthRaster r(w, h);
    r.draw(kIdentity, p, idx, faces);
    EXPECT_EQ(at(r, 4, 4) > 0.0f, drawn);
  }
}

// A triangle reaching in front of the near plane (reverse-Z: z > w) and behind the eye is drawn
// only where it lies beyond the near plane, and nothing is nearer than it (depth <= 1).
TEST(DepthRaster, ClipsAtTheNearPlane) {
  const int w = 32, h = 32;
  // Clip w = the point's z (its distance), clip z = 0.2: the near plane at distance 0.2, depth
  // 0.2 / distance. Two corners at distance 0.1 (in front of the near plane), one at 3: a floor
  // under the eye, reaching behind it.
  const std::vector<glm::vec3> p = {{-1.5f, -0.5f, 0.1f}, {1.5f, -0.5f, 0.1f}, {0.0f, -0.5f, 3.0f}};
  glm::dmat4 m(0.0);
  m[0][0] = m[1][1] = 1.0;
  m[3][2] = 0.2;
  m[2][3] = 1.0;
  DepthRaster r(w, h);
  const std::vector<uint32_t> idx = {0, 1, 2};
  r.draw(m, p, idx, DepthRaster::Faces::both);
  int covered = 0;
  for (float d : r.depth()) {
    EXPECT_LE(d, 1.0f);
    covered += d > 0.0f;
  }
  EXPECT_GT(covered, 0);
  EXPECT_LT(covered, w * h);
}

// Centres on an outline edge (GL might not cover them) are left out; along an edge shared with
// a triangle on its other side they are kept (one of the two covers them in GL too).
TEST(DepthRaster, LeavesOutCentresOnOutlinesOnly) {
  const int w = 16, h = 16;
  // A rectangle from x = 4.5 to 11.5 (edges through pixel centres) and y = 3.0 to 13.0, its
  // diagonal from (4.5, 3) to (11.5, 13).
  const std::vector<glm::vec3> p = {ndc(4.5, 3, 0.5, w, h), ndc(11.5, 3, 0.5, w, h), ndc(11.5, 13, 0.5, w, h),
                                    ndc(4.5, 13, 0.5, w, h)};
  const std::vector<uint32_t> idx = {0, 1, 2, 0, 2, 3};
  const std::vector<uint32_t> across = DepthRaster::adjacency(p, idx);
  EXPECT_EQ(across[2], 3u | DepthRaster::kReversed);  // edge 2 -> 0 of the first: the second's corner 3 across
  EXPECT_EQ(across[3], 1u | DepthRaster::kReversed);
  EXPECT_EQ(across[0], DepthRaster::kNone);  // an outline
  DepthRaster r(w, h);
  r.draw(kIdentity, p, idx, DepthRaster::Faces::both, across);
  EXPECT_EQ(at(r, 4, 8), 0.0f);   // the left edge's centres: left out
  EXPECT_EQ(at(r, 11, 8), 0.0f);  // the right edge's too
  EXPECT_GT(at(r, 5, 8), 0.0f);   // inside
  EXPECT_GT(at(r, 10, 8), 0.0f);
  // On the diagonal: centres (x + 0.5, y + 0.5) with y + 0.5 - 3 = (x + 0.5 - 4.5) * 10 / 7, e.g.
  // (11.5, 13) is a corner; none other lies exactly on it, so check every inner centre is drawn.
  for (int y = 4; y < 13; ++y)
    for (int x = 5; x < 11; ++x) EXPECT_GT(at(r, x, y), 0.0f) << x << "," << y;
}

// shows(): a quad behind the drawn depth does not show, one in front does, one beside it does,
// and one behind whose edge stops short of an uncovered centre by less than the margin does
// (GL may cover that centre).
TEST(DepthRaster, ShowsWhatLiesInFrontOrWithinTheMarginOfAHole) {
  const int w = 32, h = 32;
  auto quad = [&](double x0, double y0, double x1, double y1, double z) {
    return std::vector<glm::vec3>{ndc(x0, y0, z, w, h), ndc(x1, y0, z, w, h), ndc(x1, y1, z, w, h),
                                  ndc(x0, y1, z, w, h)};
  };
  const std::vector<uint32_t> idx = {0, 1, 2, 0, 2, 3};
  DepthRaster r(w, h);
  // Two walls with a hole between them: the column of centres x = 20.5.
  for (const auto& wall : {quad(4, 4, 20, 28, 0.5), quad(21, 4, 28, 28, 0.5)})
    r.draw(kIdentity, wall, idx, DepthRaster::Faces::both, DepthRaster::adjacency(wall, idx));
  auto shows = [&](double x0, double y0, double x1, double y1, double z) {
    const std::vector<glm::vec3> q = quad(x0, y0, x1, y1, z);
    return r.shows(kIdentity, q, idx, DepthRaster::Faces::both, DepthRaster::adjacency(q, idx));
  };
  EXPECT_FALSE(shows(8, 8, 19.9, 20, 0.3));    // behind the first wall
  EXPECT_TRUE(shows(8, 8, 19.9, 20, 0.7));     // in front of it
  EXPECT_TRUE(shows(1, 1, 3, 3, 0.3));         // beside the walls
  EXPECT_TRUE(shows(8, 8, 20.6, 20, 0.3));     // covering the hole's centres
  EXPECT_TRUE(shows(8, 8, 20.495, 20, 0.3));   // 1.3/256 pixel short of them: within the margin
  EXPECT_FALSE(shows(8, 8, 20.45, 20, 0.3));   // 13/256 short: not
  EXPECT_TRUE(shows(8, 8, 19.9, 20, 0.5 - 1e-9));  // behind the wall by less than the draw moved it back
}

// The spans' vector loops (AVX2) compute exactly the scalar loops' depths: random planes, lengths
// around the vector width, and rows holding, at random pixels, the very value the plane rounds to
// there (reaches() must count a tie; fill() must leave it).
TEST(DepthRaster, VectorSpansEqualScalarSpans) {
  if (!depth_span::vector_available()) GTEST_SKIP() << "no AVX2 on this CPU: only the scalar spans run";
  occtest::Lcg rnd{11};
  size_t ties = 0, reached = 0;
  for (int t = 0; t < 20000; ++t) {
    const int64_t n = int64_t(rnd() * 40);
    const double z0 = rnd() * 1.6 - 0.3;
    const double dz = (rnd() - 0.5) * (t % 3 == 0 ? 1e-6 : t % 3 == 1 ? 1e-3 : 0.1);
    std::vector<float> row(size_t(n) + 1);
    for (int64_t k = 0; k < n; ++k) {
      const double u = rnd();
      row[size_t(k)] = u < 0.3 ? float(z0 + dz * double(k)) : float(u * 1.2 - 0.1);
      ties += u < 0.3;
    }
    std::vector<float> a = row, b = row;
    depth_span::fill(a.data(), n, z0, dz, true);
    depth_span::fill(b.data(), n, z0, dz, false);
    ASSERT_EQ(0, std::memcmp(a.data(), b.data(), a.size() * sizeof(float))) << "n " << n << " z0 " << z0 << " dz " << dz;
    const bool v = depth_span::reaches(row.data(), n, z0, dz, true);
    ASSERT_EQ(v, depth_span::reaches(row.data(), n, z0, dz, false)) << "n " << n << " z0 " << z0 << " dz " << dz;
    reached += v;
  }
  EXPECT_GT(ties, 10000u);
  EXPECT_GT(reached, 5000u);  // both answers occur
  EXPECT_LT(reached, 19000u);
}
