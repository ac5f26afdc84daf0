#include <gtest/gtest.h>

#include "common/error.hpp"

#include <cmath>
#include <functional>

#include "common/cull/culling.hpp"
#include "common/lod/lod.hpp"
#include "scene_fixtures.hpp"

using namespace occ;
using occtest::cube_grid;

namespace {

// Fake occlusion: a box passes when it contains one of the "visible points". Records the call
// sequence to check batching.
struct FakeQueries : OcclusionQueries {
  std::vector<glm::dvec3> visible_points;
  std::vector<Aabb> boxes;
  std::vector<char> events;  // 'i' issue, 'r' result, 'e' end of batch
  uint32_t issue(const Aabb& b) override {
    events.push_back('i');
    boxes.push_back(b);
    return uint32_t(boxes.size() - 1);
  }
  uint64_t result(uint32_t h) override {
    events.push_back('r');
    uint64_t n = 0;
    for (auto& p : visible_points) n += boxes[h].contains(p);
    return n;
  }
  void end_batch() override { events.push_back('e'); }
};

Camera overview(const Aabb& b) {
  return Camera::look_at(b.center() + glm::dvec3(0, b.diagonal(), 0.01), b.center(), {0, 1, 0}, 90, 1, 0.1, 1e4);
}

}  // namespace

TEST(Culling, FrustumCullKeepsOnlyLeavesInView) {
  Scene s = cube_grid(10, 3);
  Hierarchy h = Hierarchy::build(s, {});
  Camera cam = Camera::look_at({-5, 0.5, 0.5}, {-10, 0.5, 0.5}, {0, 1, 0}, 60, 1, 0.1, 100);  // looking away
  CullStats st;
  EXPECT_TRUE(frustum_cull(h, cam, &st).empty());
  EXPECT_GT(st.frustum_culled, 0u);
  auto all = frustum_cull(h, overview(h.node(0).box));
  EXPECT_EQ(items_of_nodes(h, all).size(), h.items().size());
}

// The --window O overlay's boxes: frustum leaves not drawn themselves nor under a drawn node.
TEST(Culling, OccludedLeavesAreFrustumLeavesNotCoveredByTheDrawnNodes) {
  Scene s = cube_grid(10, 3);
  Hierarchy h = Hierarchy::build(s, {});
  const Camera all = overview(h.node(0).box);
  const std::vector<uint32_t> leaves = frustum_cull(h, all);
  ASSERT_GT(leaves.size(), 4u);
  EXPECT_EQ(occluded_leaves(h, all, {}), leaves);             // nothing drawn: every leaf in view
  EXPECT_TRUE(occluded_leaves(h, all, std::vector<uint32_t>{0}).empty());  // the root covers all
  const std::vector<uint32_t> some = {leaves[0], leaves[2]};
  std::vector<uint32_t> expected = leaves;
  std::erase(expected, leaves[0]);
  std::erase(expected, leaves[2]);
  EXPECT_EQ(occluded_leaves(h, all, some), expected);
  // An interior node (drawn at its HLOD) covers exactly its leaves.
  const uint32_t inner = h.node(leaves[1]).parent;
  ASSERT_NE(inner, kNoNode);
  for (uint32_t leaf : occluded_leaves(h, all, std::vector<uint32_t>{inner}))
    for (uint32_t n = leaf; n != kNoNode; n = h.node(n).parent) EXPECT_NE(n, inner);
  EXPECT_LT(occluded_leaves(h, all, std::vector<uint32_t>{inner}).size(), leaves.size());
  // Looking away: nothing in the frustum, nothing occluded.
  Camera away = Camera::look_at({-5, 0.5, 0.5}, {-10, 0.5, 0.5}, {0, 1, 0}, 60, 1, 0.1, 100);
  EXPECT_TRUE(occluded_leaves(h, away, {}).empty());
}

TEST(Culling, HardwareCullReturnsExactlyLeavesContainingVisiblePoints) {
  Scene s = cube_grid(12, 3);
  Hierarchy h = Hierarchy::build(s, {});
  FakeQueries q;
  q.visible_points = {{0.5, 0.5, 0.5}, {9.5, 0.5, 30.5}, {33.5, 0.5, 33.5}};
  std::vector<uint32_t> streamed;
  CullStats st;
  auto vis = hardware_cull(h, overview(h.node(0).box), q, [&](uint32_t id) { streamed.push_back(id); }, &st);
  ASSERT_EQ(vis.size(), 3u);
  std::sort(streamed.begin(), streamed.end());
  EXPECT_EQ(streamed, vis);
  for (uint32_t id : vis) {
    EXPECT_TRUE(h.node(id).leaf());
    bool has_point = false;
    for (auto& p : q.visible_points) has_point |= h.node(id).box.contains(p);
    EXPECT_TRUE(has_point);
  }
  EXPECT_EQ(st.queries, q.boxes.size());
  EXPECT_LT(st.queries, h.size());  // occluded subtrees were not descended
  EXPECT_EQ(st.levels, h.depth());
}

TEST(Culling, QueriesOfALevelAreAllIssuedBeforeAnyResultIsRead) {
  Scene s = cube_grid(8, 3);
  Hierarchy h = Hierarchy::build(s, {});
  FakeQueries q;
  for (int i = 0; i < 8; ++i) q.visible_points.push_back({3.0 * i + 0.5, 0.5, 0.5});
  hardware_cull(h, overview(h.node(0).box), q, nullptr);
  // Events look like i..i r..r e  i..i r..r e ...: within a batch no 'i' follows an 'r'.
  bool reading = false;
  for (char e : q.events) {
    if (e == 'r') reading = true;
    if (e == 'e') reading = false;
    if (e == 'i') {
      EXPECT_FALSE(reading);
    }
  }
}

TEST(Culling, BoxContainingTheEyeIsVisibleWithoutQuery) {
  Scene s = cube_grid(4, 3);
  Hierarchy h = Hierarchy::build(s, {});
  FakeQueries q;  // no visible points: every query says occluded
  Camera inside = Camera::look_at({0.5, 0.5, 0.5}, {0.5, 0.5, -5}, {0, 1, 0}, 60, 1, 0.01, 100);
  CullStats st;
  auto vis = hardware_cull(h, inside, q, nullptr, &st);
  ASSERT_EQ(vis.size(), 1u);
  EXPECT_TRUE(h.node(vis[0]).box.contains(inside.eye));
  EXPECT_GT(st.near_visible, 0u);
  for (const Aabb& b : q.boxes) {
    EXPECT_FALSE(b.contains(inside.eye));
  }
}

TEST(Culling, BoxCrossingTheNearPlaneNextToTheEyeIsVisibleWithoutQuery) {
  Camera cam = Camera::look_at({0, 0, 0}, {0, 0, -1}, {0, 1, 0}, 90, 1, 1.0, 100);
  EXPECT_TRUE(visible_without_query(Aabb{{0.5, 0.5, -2}, {3, 3, -0.9}}, cam));  // reaches inside near
  EXPECT_TRUE(visible_without_query(Aabb{{1.0, 1.0, -3}, {2, 2, -1.0}}, cam));  // touches near corner
  EXPECT_FALSE(visible_without_query(Aabb{{-1, -1, -3}, {1, 1, -2}}, cam));
}

TEST(Culling, ItemsOfNodesAreSortedAndUnique) {
  Scene s = cube_grid(5, 3);
  Hierarchy h = Hierarchy::build(s, {});
  std::vector<uint32_t> nodes{0, 3, 1};
  auto items = items_of_nodes(h, nodes);
  EXPECT_EQ(items.size(), h.items().size());
  EXPECT_TRUE(std::is_sorted(items.begin(), items.end()));
}

TEST(QuerySkipper, TrustsAfterRepeatedVisibleResultsAndResetsOnOccluded) {
  static_assert(QuerySkipper::kTrust >= 2);
  QuerySkipper s(4);
  EXPECT_FALSE(s.skip(1));
  for (int i = 1; i < QuerySkipper::kTrust; ++i) {
    s.record(1, true);
    EXPECT_FALSE(s.skip(1)) << i << " in a row are not enough";
  }
  s.record(1, true);
  EXPECT_TRUE(s.skip(1));
  EXPECT_TRUE(s.skip(1));
  EXPECT_FALSE(s.skip(1));  // wait of 2 used up: test again
  s.record(1, true);        // confirmed: the wait doubles
  int skipped = 0;
  while (s.skip(1)) ++skipped;
  EXPECT_EQ(skipped, 4);
  s.record(1, false);  // occluded: back to querying every time
  s.record(1, true);
  EXPECT_FALSE(s.skip(1));
  EXPECT_FALSE(s.skip(2));  // other nodes are independent
}

namespace {
// The cube grid from above, 32 cubes visible and half of them occluded from frame 15 on, 30
// frames: HC without adaptive queries (`plain`, the truth) and with them against `fast`;
// check(frame, with, truth) sees each frame's sets.
void occluded_half_walk(FakeQueries& fast, CullStats& plain, CullStats& skip,
                        const std::function<void(int, const std::vector<uint32_t>&, const std::vector<uint32_t>&)>& check) {
  Scene s = cube_grid(8, 3);
  Hierarchy h = Hierarchy::build(s, {});
  Renderables r(h, nullptr);
  Camera cam = overview(h.node(0).box);
  LodSelector sel(r, cam, 480, 0.0);
  FakeQueries truth_q;
  for (int i = 0; i < 8; ++i)
    for (int j = 0; j < 8; j += 2) truth_q.visible_points.push_back({3.0 * i + 0.5, 0.5, 3.0 * j + 0.5});
  fast.visible_points = truth_q.visible_points;
  QuerySkipper skipper(h.size());
  for (int frame = 0; frame < 30; ++frame) {
    if (frame == 15) {  // half of the visible cubes become occluded
      truth_q.visible_points.resize(16);
      fast.visible_points.resize(16);
    }
    auto truth = hardware_cull_lod(h, cam, truth_q, sel, {.stats = &plain});
    auto v = hardware_cull_lod(h, cam, fast, sel, {.choices = {.adaptive_queries = true}, .skipper = &skipper, .stats = &skip});
    check(frame, v, truth);
  }
}

// A querier with a cheap test (a depth pyramid's) that proves every occluded box.
struct CheapFakeQueries : FakeQueries {
  uint32_t cheap = 0;
  bool cheap_tests() const override { return true; }
  uint32_t issue_cheap(const Aabb& b) override {
    ++cheap;
    return issue(b);  // the fake's answer: exact (0 where occluded), and 1 or more otherwise
  }
};
}  // namespace

TEST(QuerySkipper, SkippedQueriesNeverLoseAVisibleNodeAndCatchUpWithOcclusion) {
  FakeQueries fast_q;
  CullStats plain_stats, skip_stats;
  occluded_half_walk(fast_q, plain_stats, skip_stats, [](int frame, const auto& fast, const auto& truth) {
    EXPECT_TRUE(std::includes(fast.begin(), fast.end(), truth.begin(), truth.end())) << "frame " << frame;
    if (frame < 15 || frame >= 15 + QuerySkipper::kMaxWait + 1) {
      EXPECT_EQ(fast, truth) << "frame " << frame;
    }
  });
  EXPECT_GT(skip_stats.skipped, 0u);
  // The occluded half is queried every frame; the visible half mostly is not.
  EXPECT_LT(skip_stats.queries, plain_stats.queries * 3 / 4) << skip_stats.queries << " vs " << plain_stats.queries;
}

// With a cheap test the leaves adaptive queries skip are tested that way, so one that becomes
// occluded leaves V in the same frame, while the full tests stay as few as without it.
TEST(QuerySkipper, CheapTestsDropASkippedLeafTheFrameItBecomesOccluded) {
  CheapFakeQueries cheap_q;
  CullStats plain_stats, skip_stats;
  uint32_t cheap_before_15 = 0;
  occluded_half_walk(cheap_q, plain_stats, skip_stats, [&](int frame, const auto& v, const auto& truth) {
    EXPECT_EQ(v, truth) << "frame " << frame;
    if (frame == 14) cheap_before_15 = cheap_q.cheap;
    if (frame == 15) {
      EXPECT_GT(cheap_q.cheap, cheap_before_15) << "the skipped leaves were tested cheaply";
    }
  });
  EXPECT_GT(skip_stats.skipped, 0u);
  EXPECT_GT(skip_stats.skipped_occluded, 0u);
  EXPECT_EQ(skip_stats.skipped + skip_stats.skipped_occluded, cheap_q.cheap);
  EXPECT_LT(skip_stats.queries, plain_stats.queries * 3 / 4) << skip_stats.queries << " vs " << plain_stats.queries;
}

TEST(QuerySkipper, HeavyLeavesAreQueriedEveryTime) {
  // Mesh 1: the cube's triangles repeated, over kMaxSkippedLeafTriangles; every other cube uses it.
  Scene s = cube_grid(4, 3);
  Mesh heavy = s.meshes[0];
  const std::vector<uint32_t> one = heavy.indices;
  while (heavy.indices.size() / 3 <= QuerySkipper::kMaxSkippedLeafTriangles)
    heavy.indices.insert(heavy.indices.end(), one.begin(), one.end());
  s.meshes.push_back(heavy);
  for (size_t k = 0; k < s.objects.size(); k += 2) s.objects[k].mesh = 1;
  Hierarchy h = Hierarchy::build(s, {});
  Renderables r(h, nullptr);
  Camera cam = overview(h.node(0).box);
  LodSelector sel(r, cam, 480, 0.0);
  FakeQueries q;
  for (const HNode& n : h.nodes())
    if (n.leaf()) q.visible_points.push_back(n.box.center());  // every cube shows
  QuerySkipper skipper(h.size());
  constexpr int kFrames = 12;
  std::vector<uint32_t> expected;
  for (uint32_t id = 0; id < h.size(); ++id)
    if (h.node(id).leaf() && h.node(id).item_count) expected.push_back(id);
  for (int frame = 0; frame < kFrames; ++frame) {
    auto v = hardware_cull_lod(h, cam, q, sel, {.choices = {.adaptive_queries = true}, .skipper = &skipper});
    EXPECT_EQ(v, expected) << "frame " << frame;
  }
  int heavy_leaves = 0, light_leaves = 0;
  for (uint32_t id : expected) {
    const HNode& n = h.node(id);
    const auto times = std::count_if(q.boxes.begin(), q.boxes.end(), [&](const Aabb& b) {
      return b.min == n.box.min && b.max == n.box.max;
    });
    if (n.triangles > QuerySkipper::kMaxSkippedLeafTriangles) {
      ++heavy_leaves;
      EXPECT_EQ(times, kFrames) << "heavy leaf " << id << " (" << n.triangles << " triangles)";
    } else {
      ++light_leaves;
      EXPECT_LT(times, kFrames / 2) << "light leaf " << id << " (" << n.triangles << " triangles)";
    }
  }
  EXPECT_EQ(heavy_leaves, 8);
  EXPECT_EQ(light_leaves, 8);
}


// Designated initializers leave the other inputs at their defaults on purpose.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmissing-field-initializers"
// The one choice of occlusion back end: auto by the renderer, tau and where the triangles are;
// a forced cpu that cannot work is one error; --adaptive-queries and --visibility-hold at auto
// come with the back end (off with cpu, on and kAutoVisibilityHold elsewhere), a setting given
// stays.
TEST(BackendChoice, AutoByRendererTauAndTrianglesForcedChoicesStayOrFailClearly) {
  auto kind = [](BackendInputs in) { return choose_backend(in, std::nullopt, std::nullopt).kind; };
  EXPECT_EQ(kind({.software_renderer = true, .renderer = "llvmpipe"}), BackendKind::cpu);
  EXPECT_EQ(kind({.software_renderer = true, .tau = 1}), BackendKind::cpu_pyramid);
  EXPECT_EQ(kind({.software_renderer = true, .triangles_in_memory = false}), BackendKind::cpu_pyramid);
  EXPECT_EQ(kind({.software_renderer = false}), BackendKind::queries);
  EXPECT_EQ(kind({.software_renderer = false, .tau = 2, .visible_pixel_lod = true}), BackendKind::queries);
  for (BackendKind k : {BackendKind::cpu, BackendKind::queries, BackendKind::gpu_pyramid, BackendKind::cpu_pyramid})
    EXPECT_EQ(kind({.flag = k, .software_renderer = k != BackendKind::cpu}), k);
  EXPECT_EQ(kind({.flag = BackendKind::cpu, .tau = 3}), BackendKind::cpu) << "tau > 0 without visible-pixel LOD";
  EXPECT_THROW(kind({.flag = BackendKind::cpu, .tau = 3, .visible_pixel_lod = true}), InputError);
  EXPECT_THROW(kind({.flag = BackendKind::cpu, .triangles_in_memory = false}), InputError);

  const BackendChoice cpu = choose_backend({.software_renderer = true, .renderer = "llvmpipe"}, std::nullopt, std::nullopt);
  EXPECT_FALSE(cpu.adaptive_queries);
  EXPECT_EQ(cpu.visibility_hold, 0);
  EXPECT_EQ(backend_line(cpu),
            "occlusion back end: cpu (auto: software renderer llvmpipe, tau 0; adaptive queries off, visibility hold 0)");
  const BackendChoice gpu = choose_backend({.software_renderer = false}, std::nullopt, std::nullopt);
  EXPECT_TRUE(gpu.adaptive_queries);
  EXPECT_EQ(gpu.visibility_hold, kAutoVisibilityHold);
  for (bool software : {false, true}) {
    const BackendChoice given = choose_backend({.software_renderer = software}, true, 5);
    EXPECT_TRUE(given.adaptive_queries);
    EXPECT_EQ(given.visibility_hold, 5);
    const BackendChoice off = choose_backend({.software_renderer = software}, false, 0);
    EXPECT_FALSE(off.adaptive_queries);
    EXPECT_EQ(off.visibility_hold, 0);
  }
}
#pragma GCC diagnostic pop
