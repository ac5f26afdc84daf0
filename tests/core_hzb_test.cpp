#include <gtest/gtest.h>

#include <optional>

#include "common/cull/hzb.hpp"
#include "random_util.hpp"

using namespace occ;

namespace {
occtest::Lcg rnd{99};

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

// random_depth and its pyramid.
std::pair<std::vector<float>, DepthPyramid> random_pyramid(int w, int h, int rects) {
  std::pair<std::vector<float>, DepthPyramid> r{random_depth(w, h, rects), DepthPyramid()};
  r.second.build(r.first, w, h);
  return r;
}

// The camera of the random boxes: at the origin looking down -z, 60 degrees, a w x h view.
Camera down_z(int w, int h) { return Camera::look_at({0, 0, 0}, {0, 0, -1}, {0, 1, 0}, 60, double(w) / h, 0.1, 100); }

// A box of half-extents up to 3 somewhere in front of a camera at the origin looking down -z.
Aabb random_box() {
  glm::dvec3 c(rnd() * 40 - 20, rnd() * 30 - 15, -(0.2 + rnd() * 60));
  glm::dvec3 e(rnd() * 3, rnd() * 3, rnd() * 3);
  return {c - e, c + e};
}

// Brute force: some pixel of the footprint has depth that does not hide the box.
bool brute_visible(const std::vector<float>& d, int w, const BoxFootprint& fp) {
  if (fp.kind != BoxFootprint::Kind::OnScreen) return fp.kind == BoxFootprint::Kind::NearPlane;
  for (int y = fp.y0; y <= fp.y1; ++y)
    for (int x = fp.x0; x <= fp.x1; ++x)
      if (!(fp.nearest_depth < d[size_t(y) * w + x])) return true;
  return false;
}

// The reverse-Z depth at which the ray through the centre of pixel (x, y) of a w x h viewport
// enters the camera-relative box [lo, hi] (inv: the inverse of projection x view rotation);
// nullopt when it misses the box.
std::optional<double> entry_depth(const glm::dmat4& vpm, const glm::dmat4& inv, int w, int h, int x, int y, const glm::dvec3& lo,
                   const glm::dvec3& hi) {
  const glm::dvec4 r = inv * glm::dvec4((x + 0.5) / w * 2 - 1, (y + 0.5) / h * 2 - 1, 0.5, 1.0);
  const glm::dvec3 dir = glm::dvec3(r) / r.w;
  double t0 = 0, t1 = 1e300;
  for (int a = 0; a < 3; ++a) {
    double ta = lo[a] / dir[a], tb = hi[a] / dir[a];
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
  }
  if (!(t0 < t1)) return std::nullopt;
  const glm::dvec4 clip = vpm * glm::dvec4(t0 * dir, 1.0);
  return clip.z / clip.w;
}

// Brute force over the pixel centres of a w x h view of a camera: whether the ray through some
// centre enters the camera-relative box [lo, hi] at a depth z that `sees(z, pixel's depth in d)`.
struct PixelCentres {
  int w, h;
  glm::dmat4 vpm, inv;
  PixelCentres(const Camera& cam, int w_, int h_)
      : w(w_), h(h_), vpm(cam.projection() * cam.view_rotation()), inv(glm::inverse(vpm)) {}
  template <class Sees>
  bool any(const std::vector<float>& d, const glm::dvec3& lo, const glm::dvec3& hi, Sees sees) const {
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const std::optional<double> z = entry_depth(vpm, inv, w, h, x, y, lo, hi);
        if (z && sees(*z, d[size_t(y) * w + x])) return true;
      }
    return false;
  }
};
}  // namespace

TEST(Hzb, PyramidLevelsHoldTheFarthestDepthBelow) {
  const int w = 37, h = 21;
  const auto [d, p] = random_pyramid(w, h, 12);
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
  const Camera cam = down_z(w, h);
  int brute_hidden = 0, hzb_hidden = 0;
  for (int trial = 0; trial < 40; ++trial) {
    const auto [d, p] = random_pyramid(w, h, 20);
    for (int i = 0; i < 250; ++i) {
      const Aabb box = random_box();
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

// What occluder fusion redrew (PixelRect): the union of the boxes' footprints, the whole viewport
// for a box the near plane cuts, nothing for one off screen; touches() as the footprints overlap.
TEST(Hzb, RedrawnPixelsAreTheUnionOfTheDrawnBoxesFootprints) {
  Camera cam = Camera::look_at({0, 0, 0}, {0, 0, -1}, {0, 1, 0}, 90, 1, 1, 100);
  const Viewport vp{64, 64};
  PixelRect r;
  EXPECT_TRUE(r.empty());
  r.add_box({{50, -1, -6}, {60, 1, -5}}, cam, vp);  // off screen
  EXPECT_TRUE(r.empty());
  const Aabb left{{-3, -1, -6}, {-2, 1, -5}}, right{{2, -1, -6}, {3, 1, -5}}, middle{{-0.1f, -0.1f, -6}, {0.1f, 0.1f, -5}};
  r.add_box(left, cam, vp);
  const BoxFootprint l = box_footprint(left, cam, vp), m = box_footprint(middle, cam, vp);
  EXPECT_EQ(r.x0, l.x0);
  EXPECT_EQ(r.x1, l.x1);
  EXPECT_FALSE(r.touches(m));  // between the two, not yet covered
  r.add_box(right, cam, vp);
  const BoxFootprint rt = box_footprint(right, cam, vp);
  EXPECT_EQ(r.x0, l.x0);
  EXPECT_EQ(r.x1, rt.x1);
  EXPECT_EQ(r.y0, std::min(l.y0, rt.y0));
  EXPECT_EQ(r.y1, std::max(l.y1, rt.y1));
  EXPECT_TRUE(r.touches(m));  // inside the union's rectangle
  EXPECT_DOUBLE_EQ(r.pixels(), double(r.x1 - r.x0 + 1) * double(r.y1 - r.y0 + 1));
  r.add_box({{-1, -1, -2}, {1, 1, 1}}, cam, vp);  // the near plane cuts it
  EXPECT_EQ(r.x0, 0);
  EXPECT_EQ(r.y0, 0);
  EXPECT_EQ(r.x1, 63);
  EXPECT_EQ(r.y1, 63);
  r.clear();
  EXPECT_TRUE(r.empty());
  EXPECT_FALSE(r.touches(m));
}

// ---- The HC pyramid probe: level choice, rectangle, depth bound; GL-free.

TEST(HzbProbe, LevelCountHalvesRoundingUpToOneTexel) {
  EXPECT_EQ(pyramid_level_count({1, 1}), 1u);
  EXPECT_EQ(pyramid_level_count({2, 1}), 2u);
  EXPECT_EQ(pyramid_level_count({1024, 1024}), 11u);
  EXPECT_EQ(pyramid_level_count({1025, 3}), 12u);  // 1025 513 257 129 65 33 17 9 5 3 2 1
  EXPECT_EQ(pyramid_level_count({203, 117}), 9u);  // 203 102 51 26 13 7 4 2 1
  DepthPyramid p;
  p.build(std::vector<float>(203 * 117, 0.5f), 203, 117);
  EXPECT_EQ(p.level_count(), pyramid_level_count({203, 117}));
}

TEST(HzbProbe, LevelForIsTheLowestWhereTheRectangleSpansAtMostSpanTexels) {
  const uint32_t levels = pyramid_level_count({256, 256});
  for (int span : {2, 4, 16})
    for (int x0 = 0; x0 < 256; x0 += 7)
      for (int w = 1; x0 + w <= 256; w += 5) {
        const int x1 = x0 + w - 1, y0 = (x0 * 3) % 200, y1 = std::min(255, y0 + w / 2);
        const uint32_t l = pyramid_level_for(x0, y0, x1, y1, levels, span);
        ASSERT_LT(l, levels);
        EXPECT_LE((x1 >> l) - (x0 >> l) + 1, span) << x0 << ".." << x1 << " level " << l;
        EXPECT_LE((y1 >> l) - (y0 >> l) + 1, span);
        if (l > 0) {  // one level lower it would span more
          EXPECT_TRUE((x1 >> (l - 1)) - (x0 >> (l - 1)) + 1 > span || (y1 >> (l - 1)) - (y0 >> (l - 1)) + 1 > span);
        }
      }
  EXPECT_EQ(pyramid_level_for(5, 5, 5, 5, levels, 2), 0u);
  EXPECT_EQ(pyramid_level_for(0, 0, 255, 255, levels, 2), 7u);  // 2 x 2 texels of 128 pixels
  EXPECT_EQ(pyramid_level_for(127, 0, 128, 0, levels, 2), 0u);  // 2 pixels across the middle
  EXPECT_EQ(pyramid_level_for(126, 0, 129, 0, levels, 2), 1u);  // 63..64
  EXPECT_EQ(pyramid_level_for(63, 0, 192, 0, levels, 2), 7u);   // 130 pixels straddling 128: 0..1 at 128
  EXPECT_EQ(pyramid_level_for(63, 0, 192, 0, levels, 4), 6u);   // 0..3 at 64
}

TEST(HzbProbe, ProbeCoversTheBoxFootprintAndBoundsItsDepth) {
  const Viewport vp{160, 120};
  Camera cam = Camera::look_at({3, 1, 2}, {3, 1, -10}, {0, 1, 0}, 60, double(vp.width) / vp.height, 0.1, 100);
  int probes = 0;
  for (int i = 0; i < 2000; ++i) {
    glm::dvec3 c(3 + rnd() * 40 - 20, 1 + rnd() * 30 - 15, 2 - (0.05 + rnd() * 80));
    glm::dvec3 e(rnd() * 3, rnd() * 3, rnd() * 0.01 + (i % 2) * rnd() * 3);
    const Aabb box{c - e, c + e};
    const BoxFootprint fp = box_footprint(box, cam, vp);
    for (int span : {2, 16}) {
      const PyramidProbe p = pyramid_probe(box, cam, vp, 1e-5, span);
      if (fp.kind == BoxFootprint::Kind::NearPlane) {
        // Clipped by the near plane: probed where its part in the view volume lies, never
        // proven where that part reaches the near plane on screen (box_in_view_vertices).
        EXPECT_NE(p.kind, PyramidProbe::Kind::no_samples);
        continue;
      }
      if (p.kind != PyramidProbe::Kind::probe) continue;
      ++probes;
      ASSERT_EQ(fp.kind, BoxFootprint::Kind::OnScreen);
      // The probe's texels cover every pixel of the (unpadded) footprint.
      EXPECT_LE(p.x0 << p.level, fp.x0);
      EXPECT_LE(p.y0 << p.level, fp.y0);
      EXPECT_GE(((p.x1 + 1) << p.level) - 1, fp.x1);
      EXPECT_GE(((p.y1 + 1) << p.level) - 1, fp.y1);
      EXPECT_LE(p.x1 - p.x0 + 1, span);
      EXPECT_LE(p.y1 - p.y0 + 1, span);
      // Its depth bound is at least the nearest corner's depth, and not much more.
      EXPECT_GE(p.depth, fp.nearest_depth);
      EXPECT_LE(p.depth, fp.nearest_depth * 1.002f + 1e-6f);
    }
  }
  EXPECT_GT(probes, 1000);
}

TEST(HzbProbe, EmptyBoxesHaveNoSamplesAndBoxesAtTheEyeOrOffScreenAreQueried) {
  Camera cam = Camera::look_at({0, 0, 0}, {0, 0, -1}, {0, 1, 0}, 90, 1, 1, 100);
  EXPECT_EQ(pyramid_probe(Aabb{}, cam, {64, 64}, 1e-5).kind, PyramidProbe::Kind::no_samples);
  // Eye inside: the part in view reaches the near plane on screen, so the bound is the near
  // plane's depth (1) or more: nothing can prove it occluded.
  const PyramidProbe inside = pyramid_probe({{-1, -1, -2}, {1, 1, 1}}, cam, {64, 64}, 1e-5);
  EXPECT_TRUE(inside.kind == PyramidProbe::Kind::query || inside.depth >= 1.0f);
  EXPECT_EQ(pyramid_probe({{-1, -1, 5}, {1, 1, 6}}, cam, {64, 64}, 1e-5).kind, PyramidProbe::Kind::query);   // behind
  // Just beyond the near plane (1), within the margin: bounded through the part in view.
  const Aabb just{{-0.1, -0.1, -1.2}, {0.1, 0.1, -1.0005}};
  const PyramidProbe justp = pyramid_probe(just, cam, {64, 64}, 1e-5);
  ASSERT_EQ(justp.kind, PyramidProbe::Kind::probe);
  EXPECT_GE(justp.depth, box_footprint(just, cam, {64, 64}).nearest_depth);
  EXPECT_EQ(pyramid_probe({{-0.1, -0.1, -1.2}, {0.1, 0.1, -1.01}}, cam, {64, 64}, 1e-5).kind, PyramidProbe::Kind::probe);
  // Beside the eye, reaching behind it: its part in view is off to the side and farther away, so
  // it is probed with a bound below the near plane's depth.
  const PyramidProbe beside = pyramid_probe({{3, -1, -20}, {4, 1, 5}}, cam, {64, 64}, 1e-5);
  ASSERT_EQ(beside.kind, PyramidProbe::Kind::probe);
  EXPECT_LT(beside.depth, 0.5f);
  EXPECT_GT(beside.x0, 0) << "on the right-hand side";
  EXPECT_EQ(pyramid_probe({{50, -1, -6}, {60, 1, -5}}, cam, {64, 64}, 1e-5).kind, PyramidProbe::Kind::query);  // off screen
}

// The probe test on a CPU depth buffer against brute force over the padded box's pixels: never
// "occluded" where a pixel of the footprint is not strictly in front of the box; and finer spans
// prove at least as much as coarser ones.
TEST(HzbProbe, OccludesNeverWhereBruteForceSeesAPixelAndFinerSpansProveMore) {
  const int w = 160, h = 120;
  const Camera cam = down_z(w, h);
  int brute_hidden = 0, proven2 = 0, proven16 = 0;
  for (int trial = 0; trial < 30; ++trial) {
    const auto [d, p] = random_pyramid(w, h, 20);
    for (int i = 0; i < 250; ++i) {
      const Aabb box = random_box();
      const BoxFootprint fp = box_footprint(box, cam, {w, h});
      const bool brute = brute_visible(d, w, fp);
      const PyramidProbe p2 = pyramid_probe(box, cam, {w, h}, 1e-5, 2), p16 = pyramid_probe(box, cam, {w, h}, 1e-5, 16);
      const bool o2 = p.occludes(p2), o16 = p.occludes(p16);
      ASSERT_TRUE(!brute || (!o2 && !o16)) << "false cull at trial " << trial << " box " << i;
      EXPECT_TRUE(!o2 || o16) << "span 16 proves what span 2 proves";
      brute_hidden += !brute;
      proven2 += o2;
      proven16 += o16;
    }
  }
  EXPECT_GT(brute_hidden, 100);
  EXPECT_GT(proven16, proven2);
  EXPECT_GT(proven2, brute_hidden / 4);
}

// The refined occlusion proof (DepthPyramid::occludes_refined) on random rectangles against brute
// force over every pixel centre (the ray through it enters the box, padded, at a depth not behind
// the pixel's): never "occluded" where a centre sees the box; everything the probe proves; and
// most of what brute force finds hidden, far more than the probe.
TEST(HzbRefined, ProvesOnlyWhatNoPixelCentreSeesAndMoreThanTheProbe) {
  const int w = 160, h = 120;
  const Camera cam = down_z(w, h);
  const PixelCentres centres(cam, w, h);
  int probed = 0, brute_hidden = 0, probe_proven = 0, refined_proven = 0;
  for (int trial = 0; trial < 20; ++trial) {
    const auto [d, p] = random_pyramid(w, h, 20);
    for (int i = 0; i < 200; ++i) {
      Aabb box = random_box();
      if (i % 3 == 0) {  // thin slanted slabs: the probe's rectangle covers far more than the box does
        const int a = i % 2;
        box.max[a] = box.min[a] + 0.01;
        box.min[2] -= 10;
      }
      const PyramidProbe pr = pyramid_probe(box, cam, {w, h}, 1e-5);
      if (pr.kind != PyramidProbe::Kind::probe) continue;
      ++probed;
      const glm::dvec3 lo = box.min - 1e-4, hi = box.max + 1e-4;  // a little more than the pad
      const bool brute = centres.any(d, lo, hi, [](double z, float depth) { return !(z < depth); });
      const bool probe = p.occludes(pr), refined = p.occludes_refined(pr, box, cam, 1e-5, 1 << 20);
      ASSERT_TRUE(!brute || !refined) << "proves occluded a box a pixel centre sees, trial " << trial << " box " << i;
      ASSERT_TRUE(!probe || refined) << "the refined test proves what the probe proves, trial " << trial << " box " << i;
      brute_hidden += !brute;
      probe_proven += probe;
      refined_proven += refined;
    }
  }
  std::printf("%d boxes probed, %d hidden (brute force), %d proven by the probe, %d by the refined test\n", probed,
              brute_hidden, probe_proven, refined_proven);
  EXPECT_GT(brute_hidden, probed / 5);
  EXPECT_GT(refined_proven, brute_hidden * 3 / 4);
  EXPECT_GT(refined_proven, probe_proven + probe_proven / 4);
}

// DepthPyramid::shows (the CPU proof that a box's query counts a sample) on synthetic buffers: a
// cleared buffer shows nearly every box wholly in front of the near plane that is on screen; a buffer at
// the near plane shows none; on random rectangles it claims a box only where brute force over the
// pixel centres (ray through the centre enters the box at a depth nearer than the pixel's) agrees.
TEST(HzbShows, ProvesOnlyWhatBruteForceOverPixelCentresSees) {
  const int w = 160, h = 120;
  const Camera cam = down_z(w, h);
  const PixelCentres centres(cam, w, h);
  DepthPyramid cleared, nearest;
  cleared.build(std::vector<float>(size_t(w) * h, 0.0f), w, h);
  nearest.build(std::vector<float>(size_t(w) * h, 1.0f), w, h);
  int probed = 0, brute_shows = 0, shown = 0, shown_cleared = 0;
  for (int trial = 0; trial < 20; ++trial) {
    const auto [d, p] = random_pyramid(w, h, 20);
    for (int i = 0; i < 200; ++i) {
      const Aabb box = random_box();
      const bool in_front = pyramid_probe(box, cam, {w, h}, 1e-5).kind == PyramidProbe::Kind::probe;
      EXPECT_FALSE(nearest.shows(box, cam));
      if (in_front) {
        ++probed;
        shown_cleared += cleared.shows(box, cam);
      }
      const bool brute =
          centres.any(d, box.min - cam.eye, box.max - cam.eye, [](double z, float depth) { return z > depth; });
      const bool s = p.shows(box, cam);
      ASSERT_TRUE(brute || !s) << "shows a box no pixel centre sees, trial " << trial << " box " << i;
      brute_shows += brute;
      shown += s;
    }
  }
  EXPECT_GT(probed, 1000);
  EXPECT_GT(shown_cleared, probed * 9 / 10) << "a cleared buffer shows nearly every box (not those between pixel centres)";
  EXPECT_GT(brute_shows, probed / 4);
  EXPECT_GT(shown, brute_shows / 2) << "the proof finds most of them";
}

// After level 0 changes inside a rectangle, rebuilding the levels above it alone gives the pyramid
// a full build of the new buffer gives (cpu-pyramid's refresh after occluder fusion).
TEST(Hzb, RebuildingTheLevelsAboveAChangedRectangleEqualsAFullBuild) {
  for (auto [w, h] : {std::pair{37, 21}, {64, 64}, {203, 117}}) {
    auto [d, part] = random_pyramid(w, h, 12);
    for (int round = 0; round < 20; ++round) {
      const int x0 = int(rnd() * w), y0 = int(rnd() * h);
      const int x1 = std::min(w - 1, x0 + int(rnd() * w / 3)), y1 = std::min(h - 1, y0 + int(rnd() * h / 3));
      float* l0 = part.level0(w, h);
      for (int y = y0; y <= y1; ++y)
        for (int x = x0; x <= x1; ++x) {
          const float z = float(rnd());
          d[size_t(y) * w + x] = z;
          l0[size_t(y) * w + x] = z;
        }
      part.build_levels(x0, y0, x1, y1);
      DepthPyramid full;
      full.build(d, w, h);
      for (size_t l = 0; l < full.level_count(); ++l) {
        const int lw = (w + (1 << l) - 1) >> l, lh = (h + (1 << l) - 1) >> l;
        for (int y = 0; y < lh; ++y)
          for (int x = 0; x < lw; ++x)
            ASSERT_EQ(part.texel(l, x, y), full.texel(l, x, y)) << w << "x" << h << " round " << round << " level " << l;
      }
    }
  }
}
