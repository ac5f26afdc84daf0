#include <gtest/gtest.h>

#include "common/hzb.hpp"

using namespace occ;

namespace {
uint64_t rng_state = 99;
double rnd() {
  rng_state = rng_state * 6364136223846793005ULL + 1442695040888963407ULL;
  return double(rng_state >> 11) / double(1ULL << 53);
}

// A depth buffer of random axis-aligned rectangles at random depths over a cleared (0) buffer.
std::vector<float> random_depth(int w, int h, int rects) {
  std::vector<float> d(size_t(w) * h, 0.0f);
  for (int r = 0; r < rects; ++r) {
    int x0 = int(rnd() * w), y0 = int(rnd() * h), x1 = std::min(w, x0 + 1 + int(rnd() * w / 2)),
        y1 = std::min(h, y0 + 1 + int(rnd() * h / 2));
    float z = float(0.2 + 0.8 * rnd());
    for (int y = y0; y < y1; ++y)
      for (int x = x0; x < x1; ++x) d[size_t(y) * w + x] = std::max(d[size_t(y) * w + x], z);
  }
  return d;
}

// Brute force: some pixel of the footprint has depth that does not hide the box.
bool brute_visible(const std::vector<float>& d, int w, const BoxFootprint& fp) {
  if (fp.kind != BoxFootprint::Kind::OnScreen) return fp.kind == BoxFootprint::Kind::NearPlane;
  for (int y = fp.y0; y <= fp.y1; ++y)
    for (int x = fp.x0; x <= fp.x1; ++x)
      if (!(fp.nearest_depth < d[size_t(y) * w + x])) return true;
  return false;
}
}  // namespace

TEST(Hzb, PyramidLevelsHoldTheFarthestDepthBelow) {
  const int w = 37, h = 21;
  auto d = random_depth(w, h, 12);
  DepthPyramid p;
  p.build(d, w, h);
  ASSERT_EQ(p.texel(0, 5, 7), d[7 * w + 5]);
  for (size_t l = 1; l < p.level_count(); ++l) {
    const int lw = (w + (1 << l) - 1) >> l, lh = (h + (1 << l) - 1) >> l;
    for (int y = 0; y < lh; ++y)
      for (int x = 0; x < lw; ++x) {
        float m = 1;
        for (int sy = y << l; sy < std::min(h, (y + 1) << l); ++sy)
          for (int sx = x << l; sx < std::min(w, (x + 1) << l); ++sx) m = std::min(m, d[size_t(sy) * w + sx]);
        ASSERT_EQ(p.texel(l, x, y), m) << "level " << l << " texel " << x << "," << y;
      }
  }
}

TEST(Hzb, NeverCullsABoxThatBruteForceSeesAndCullsMost) {
  const int w = 160, h = 120;
  Camera cam = Camera::look_at({0, 0, 0}, {0, 0, -1}, {0, 1, 0}, 60, double(w) / h, 0.1, 100);
  int brute_hidden = 0, hzb_hidden = 0;
  for (int trial = 0; trial < 40; ++trial) {
    auto d = random_depth(w, h, 20);
    DepthPyramid p;
    p.build(d, w, h);
    for (int i = 0; i < 250; ++i) {
      glm::dvec3 c(rnd() * 40 - 20, rnd() * 30 - 15, -(0.2 + rnd() * 60));
      glm::dvec3 e(rnd() * 3, rnd() * 3, rnd() * 3);
      Aabb box{c - e, c + e};
      BoxFootprint fp = box_footprint(box, cam, {w, h});
      bool brute = brute_visible(d, w, fp), hzb = p.may_be_visible(fp);
      ASSERT_TRUE(hzb || !brute) << "false cull at trial " << trial << " box " << i;
      brute_hidden += !brute;
      hzb_hidden += !hzb;
    }
  }
  EXPECT_GT(brute_hidden, 100);
  EXPECT_GT(hzb_hidden, brute_hidden / 2);  // the pyramid is conservative, not useless
}

TEST(Hzb, FootprintFlagsBoxesAtTheNearPlaneAndOffscreen) {
  Camera cam = Camera::look_at({0, 0, 0}, {0, 0, -1}, {0, 1, 0}, 90, 1, 1, 100);
  EXPECT_EQ(box_footprint({{-1, -1, -2}, {1, 1, 1}}, cam, {64, 64}).kind, BoxFootprint::Kind::NearPlane);
  EXPECT_EQ(box_footprint({{-1, -1, 5}, {1, 1, 6}}, cam, {64, 64}).kind, BoxFootprint::Kind::NearPlane);
  EXPECT_EQ(box_footprint({{50, -1, -6}, {60, 1, -5}}, cam, {64, 64}).kind, BoxFootprint::Kind::Offscreen);
  BoxFootprint fp = box_footprint({{-1, -1, -6}, {1, 1, -4}}, cam, {64, 64});
  ASSERT_EQ(fp.kind, BoxFootprint::Kind::OnScreen);
  EXPECT_LE(fp.x0, 32 - 8);  // |x| <= 1/4 of the half-width at depth 4
  EXPECT_GE(fp.x1, 32 + 7);
  // Nearest corner at distance 4 with near 1, far 100: reverse-Z depth n(f-d)/(d(f-n)).
  EXPECT_NEAR(fp.nearest_depth, 1.0 * (100 - 4) / (4 * 99.0), 1e-6);
}
