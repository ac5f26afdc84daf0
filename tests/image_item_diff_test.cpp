// The tau checker's arithmetic (render_client/tools/item_diff.hpp, frame_diff --items) on
// hand-made item buffers: the exact distance transform, a surface moved by k pixels, a missing
// object, an HLOD standing for its items, slivers, and the id-space file.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <initializer_list>
#include <utility>
#include <filesystem>
#include <random>

#include <unistd.h>

#include "render_client/tools/item_diff.hpp"

using namespace occ;

namespace {

// 4 items; node 0 (root) holds items 0..3, node 1 items 0..1, node 2 items 2..3.
ItemSpace space() { return ItemSpace{4, {{0, 4}, {0, 2}, {2, 2}}}; }
constexpr uint32_t kHlod1 = 4 + 1 + 1;  // the value of node 1 drawn as its HLOD

IdImage blank(int w = 32, int h = 24) { return IdImage{w, h, std::vector<uint32_t>(size_t(w) * h, 0), {}}; }

// Fills [x0, x1) x [y0, y1) with `value` (item index + 1, or an HLOD value).
void rect(IdImage& img, int x0, int y0, int x1, int y1, uint32_t value) {
  for (int y = y0; y < y1; ++y)
    for (int x = x0; x < x1; ++x) img.ids[size_t(y) * img.width + x] = value;
}

struct Rect {
  int x0, y0, x1, y1;
  uint32_t value;
};
// A reference of `rects` (drawn in order) and a frame: its copy with `changes` drawn over it.
std::pair<IdImage, IdImage> buffers(std::initializer_list<Rect> rects, std::initializer_list<Rect> changes) {
  std::pair<IdImage, IdImage> b{blank(), blank()};
  for (const Rect& r : rects) rect(b.first, r.x0, r.y0, r.x1, r.y1, r.value);
  b.second = b.first;
  for (const Rect& r : changes) rect(b.second, r.x0, r.y0, r.x1, r.y1, r.value);
  return b;
}

// Gives `img` a depth: `near` of each value (larger is nearer: reverse-Z), background 0.
void with_depth(IdImage& img, const std::function<float(uint32_t)>& near) {
  img.depth.resize(img.ids.size());
  for (size_t p = 0; p < img.ids.size(); ++p) img.depth[p] = img.ids[p] ? near(img.ids[p]) : 0.0f;
}
float by_value(uint32_t v) { return 0.1f * float(v); }

TEST(ItemDiff, DistanceTransformIsExactEuclidean) {
  std::mt19937 rng(7);
  const int w = 37, h = 23;
  for (int round = 0; round < 20; ++round) {
    std::vector<double> f(size_t(w) * h, kFar);
    std::vector<std::pair<int, int>> sites;
    for (int k = 0; k < 1 + round % 6; ++k) {
      const int x = int(rng() % w), y = int(rng() % h);
      sites.emplace_back(x, y);
      f[size_t(y) * w + x] = 0;
    }
    squared_distance_transform(f, w, h);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        double best = kFar;
        for (auto [sx, sy] : sites) best = std::min(best, double((x - sx) * (x - sx) + (y - sy) * (y - sy)));
        ASSERT_EQ(f[size_t(y) * w + x], best) << x << "," << y;
      }
  }
}

TEST(ItemDiff, IdenticalBuffersHaveNoError) {
  IdImage ref = blank();
  rect(ref, 2, 2, 10, 10, 1);
  rect(ref, 12, 4, 20, 9, 3);
  const ItemDiff d = diff_items(space(), ref, ref, 1.0);
  EXPECT_EQ(d.shown, 2u);
  EXPECT_EQ(d.missing, 0u);
  EXPECT_EQ(d.max_displacement, 0.0);
  EXPECT_EQ(d.beyond_tau, 0u);
  EXPECT_EQ(d.drawn, 8u * 8 + 8 * 5);
}

TEST(ItemDiff, ASurfaceMovedByKPixelsIsDisplacedByK) {
  for (int k = 1; k <= 6; ++k) {
    IdImage ref = blank(), tau = blank();
    rect(ref, 4, 4, 14, 14, 2);
    rect(tau, 4 + k, 4, 14 + k, 14, 2);  // moved right by k
    with_depth(ref, by_value);
    with_depth(tau, by_value);
    const ItemDiff d = diff_items(space(), ref, tau, 2.0);
    EXPECT_EQ(d.missing, 0u) << k;
    EXPECT_DOUBLE_EQ(d.max_displacement, double(k)) << k;
    EXPECT_DOUBLE_EQ(d.max_thick_displacement, double(k)) << k;
    // The column 4+k .. 14+k side gained k columns, the left side lost k: 2 * k * 10 wrong pixels,
    // those more than 2 pixels from the edge they moved across count.
    EXPECT_EQ(d.beyond_tau, uint64_t(k > 2 ? 2 * (k - 2) * 10 : 0)) << k;
  }
  // Diagonally by (3, 4): 5 pixels.
  IdImage ref = blank(), tau = blank();
  rect(ref, 2, 2, 12, 12, 1);
  rect(tau, 5, 6, 15, 16, 1);
  with_depth(ref, by_value);
  with_depth(tau, by_value);
  EXPECT_DOUBLE_EQ(diff_items(space(), ref, tau, 1.0).max_displacement, 5.0);
}

TEST(ItemDiff, AnUncoveredObjectIsChargedToTheOccluderThatMoved) {
  // Item 0 behind item 1: the reference shows a sliver of 0 far away only. Item 1's edge moves
  // down by one pixel: the uncovered row of 0 is one pixel from where 1 still is.
  auto [ref, tau] = buffers({{0, 10, 32, 20, 2}, {30, 5, 32, 10, 1}}, {{0, 10, 30, 11, 1}});
  with_depth(ref, by_value);  // item 1 (value 2) in front of item 0
  with_depth(tau, by_value);
  ItemDiff d = diff_items(space(), ref, tau, 1.0);
  EXPECT_DOUBLE_EQ(d.max_displacement, 1.0);
  EXPECT_EQ(d.beyond_tau, 0u);
  // Had item 0 come in front of item 1 instead, it would have come 30 pixels from where it was.
  with_depth(ref, [](uint32_t v) { return 1.0f / float(v); });
  with_depth(tau, [](uint32_t v) { return 1.0f / float(v); });
  d = diff_items(space(), ref, tau, 1.0);
  EXPECT_DOUBLE_EQ(d.max_displacement, std::sqrt(30.0 * 30.0 + 1.0));  // (0, 10) to (30, 9)
  // Without depth: the smaller of the two.
  ref.depth.clear();
  tau.depth.clear();
  EXPECT_DOUBLE_EQ(diff_items(space(), ref, tau, 1.0).max_displacement, 1.0);
}

TEST(ItemDiff, AMissingObjectCountsOne) {
  IdImage ref = blank(), tau = blank();
  rect(ref, 2, 2, 6, 6, 1);
  rect(ref, 10, 10, 11, 11, 4);  // item 3, one pixel
  rect(tau, 2, 2, 6, 6, 1);
  const ItemDiff d = diff_items(space(), ref, tau, 1.0);
  EXPECT_EQ(d.shown, 2u);
  EXPECT_EQ(d.missing, 1u);
  EXPECT_EQ(d.first_missing, 3u);
  EXPECT_EQ(d.missing_pixels, 1u);
  EXPECT_EQ(d.missing_x, 10);
  EXPECT_EQ(d.missing_y, 10);
}

TEST(ItemDiff, AnHlodStandsForTheItemsItHolds) {
  IdImage ref = blank(), tau = blank();
  rect(ref, 2, 2, 8, 8, 1);    // item 0
  rect(ref, 8, 2, 14, 8, 2);   // item 1
  rect(ref, 20, 2, 24, 8, 3);  // item 2
  rect(tau, 2, 2, 15, 8, kHlod1);  // node 1's HLOD: items 0 and 1, one column wider
  rect(tau, 20, 2, 24, 8, 3);
  with_depth(ref, by_value);
  with_depth(tau, by_value);
  ItemDiff d = diff_items(space(), ref, tau, 1.0);
  EXPECT_EQ(d.missing, 0u);
  EXPECT_DOUBLE_EQ(d.max_displacement, 1.0);
  // The same HLOD over item 2's place: item 2 is not one of node 1's, so it is missing, and the
  // HLOD's pixels there are 6 columns from its nearest item.
  rect(tau, 20, 2, 24, 8, kHlod1);
  with_depth(tau, by_value);
  d = diff_items(space(), ref, tau, 1.0);
  EXPECT_EQ(d.missing, 1u);
  EXPECT_EQ(d.first_missing, 2u);
  // An HLOD value outside the space is refused.
  rect(tau, 0, 0, 1, 1, 4 + 3 + 1);
  EXPECT_THROW(diff_items(space(), ref, tau, 1.0), std::runtime_error);
}

TEST(ItemDiff, SliversAreExcusedFromTheThickBound) {
  // A one-pixel line of item 0 on item 1 that the tau frame lost for 16 pixels of its length.
  auto [ref, tau] = buffers({{0, 4, 32, 20, 2}, {4, 12, 28, 13, 1}}, {{4, 12, 20, 13, 2}});
  with_depth(ref, [](uint32_t v) { return v == 1 ? 0.6f : 0.5f; });  // the line in front
  with_depth(tau, [](uint32_t v) { return v == 1 ? 0.6f : 0.5f; });
  ItemDiff d = diff_items(space(), ref, tau, 1.0);
  EXPECT_EQ(d.missing, 0u);
  EXPECT_DOUBLE_EQ(d.max_displacement, 16.0);  // where the line still is
  EXPECT_EQ(d.max_thick_displacement, 0.0);
  EXPECT_EQ(d.thin, 16u);
  // Two pixels thick: still a sliver. Three: not, and a thick item missing counts.
  rect(ref, 4, 13, 28, 14, 1);
  with_depth(ref, [](uint32_t v) { return v == 1 ? 0.6f : 0.5f; });
  EXPECT_EQ(diff_items(space(), ref, tau, 1.0).max_thick_displacement, 0.0);
  rect(ref, 4, 14, 28, 15, 1);
  with_depth(ref, [](uint32_t v) { return v == 1 ? 0.6f : 0.5f; });
  d = diff_items(space(), ref, tau, 1.0);
  EXPECT_DOUBLE_EQ(d.max_thick_displacement, std::sqrt(16.0 * 16.0 + 2.0 * 2.0));  // (4, 14) to (20, 12)
  rect(tau, 20, 12, 28, 13, 2);  // the frame lost the whole line
  d = diff_items(space(), ref, tau, 1.0);
  EXPECT_EQ(d.missing, 1u);
  EXPECT_EQ(d.missing_thick, 1u);
}

TEST(ItemDiff, IdSpaceFileRoundTripsAndIdsEncodeAsRgba) {
  const std::string path = (std::filesystem::temp_directory_path() / ("occ_items_" + std::to_string(::getpid()))).string();
  space().write(path);
  EXPECT_EQ(ItemSpace::read(path), space());
  std::filesystem::remove(path);
  EXPECT_EQ(space().range(0), std::make_pair(0u, 0u));
  EXPECT_EQ(space().range(3), std::make_pair(2u, 3u));
  EXPECT_EQ(space().range(kHlod1), std::make_pair(0u, 2u));
  IdImage ids = blank(3, 2);
  ids.ids = {0, 1, 0x01020304u, 0xffffffffu, 256, 7};
  EXPECT_EQ(decode_ids(encode_ids(ids)).ids, ids.ids);
  EXPECT_EQ(encode_ids(ids).rgba[8], 4);  // little-endian: low byte in R
}

}  // namespace
