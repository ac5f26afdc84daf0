#include <gtest/gtest.h>

#include <cmath>

#include "common/culling.hpp"
#include "common/lod.hpp"
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

TEST(Culling, ProjectedBoxAreaIsTheCoveredPixels) {
  // 60 degrees, 480 px high: at 10 m a 2 x 2 m face spans 2 * 240 / (10 tan 30) = 83.1 px.
  const Camera cam = Camera::look_at({0, 0, 0}, {0, 0, -1}, {0, 1, 0}, 60, 1, 0.1, 100);
  const double side = 480.0 / (10.0 * std::tan(glm::radians(30.0)));
  EXPECT_NEAR(projected_box_area_px(Aabb{{-1, -1, -10}, {1, 1, -10}}, cam, 480), side * side, 1e-6 * side * side);
  // A deep box shows its near face (at 9 m), which holds the far face's projection.
  const double near_side = 480.0 / (9.0 * std::tan(glm::radians(30.0)));
  EXPECT_NEAR(projected_box_area_px(Aabb{{-1, -1, -10}, {1, 1, -8}}, cam, 480), near_side * near_side * 81.0 / 64.0,
              1e-6 * near_side * near_side);
  // Off-axis: more than the face (a side shows too).
  const double off = projected_box_area_px(Aabb{{3, -1, -10}, {5, 1, -8}}, cam, 480);
  EXPECT_GT(off, side * side);
  EXPECT_TRUE(std::isinf(projected_box_area_px(Aabb{{-1, -1, -1}, {1, 1, 1}}, cam, 480))) << "eye inside";
  EXPECT_TRUE(std::isinf(projected_box_area_px(Aabb{{-1, -1, 1}, {1, 1, 2}}, cam, 480))) << "behind";
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

TEST(QuerySkipper, SkippedQueriesNeverLoseAVisibleNodeAndCatchUpWithOcclusion) {
  Scene s = cube_grid(8, 3);
  Hierarchy h = Hierarchy::build(s, {});
  Renderables r(h, nullptr);
  Camera cam = overview(h.node(0).box);
  LodSelector sel(r, cam, 480, 0.0);
  FakeQueries truth_q, fast_q;
  for (int i = 0; i < 8; ++i)
    for (int j = 0; j < 8; j += 2) truth_q.visible_points.push_back({3.0 * i + 0.5, 0.5, 3.0 * j + 0.5});
  fast_q.visible_points = truth_q.visible_points;
  QuerySkipper skipper(h.size());
  CullStats plain_stats, skip_stats;
  for (int frame = 0; frame < 30; ++frame) {
    if (frame == 15) {  // half of the visible cubes become occluded
      truth_q.visible_points.resize(16);
      fast_q.visible_points.resize(16);
    }
    auto truth = hardware_cull_lod(h, cam, truth_q, sel, {.stats = &plain_stats});
    auto fast = hardware_cull_lod(h, cam, fast_q, sel, {.skipper = &skipper, .stats = &skip_stats});
    EXPECT_TRUE(std::includes(fast.begin(), fast.end(), truth.begin(), truth.end())) << "frame " << frame;
    if (frame < 15 || frame >= 15 + QuerySkipper::kMaxWait + 1) {
      EXPECT_EQ(fast, truth) << "frame " << frame;
    }
  }
  EXPECT_GT(skip_stats.skipped, 0u);
  // The occluded half is queried every frame; the visible half mostly is not.
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
    auto v = hardware_cull_lod(h, cam, q, sel, {.skipper = &skipper});
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

namespace {

// Geometry queries (LeafTest::geometry): a box passes as in FakeQueries; a leaf's geometry shows
// when its node's box holds one of `geometry_points` (where its geometry is the nearest surface).
// Renderables in `blended` cannot be tested. Events: 'g' geometry issued, 'R' geometry result.
struct GeometryFakeQueries : FakeQueries {
  static constexpr uint32_t kBit = 0x80000000u;
  const Hierarchy* h = nullptr;
  std::vector<glm::dvec3> geometry_points;
  std::vector<uint32_t> blended;
  std::vector<uint32_t> tested;  // renderables, by geometry handle
  bool geometry_queries() const override { return true; }
  uint32_t issue_geometry(uint32_t renderable) override {
    events.push_back('g');
    if (std::find(blended.begin(), blended.end(), renderable) != blended.end()) return kNoGeometryQuery;
    tested.push_back(renderable);
    return kBit | uint32_t(tested.size() - 1);
  }
  uint64_t result(uint32_t handle) override {
    if (!(handle & kBit)) return FakeQueries::result(handle);
    events.push_back('R');
    uint64_t n = 0;
    for (auto& p : geometry_points) n += h->node(tested.at(handle & ~kBit)).box.contains(p);  // level-0 ids = nodes
    return n;
  }
};

struct GeometryGrid {
  Scene s = cube_grid(12, 3);
  Hierarchy h = Hierarchy::build(s, {});
  Renderables r{h, nullptr};
  Camera cam = overview(h.node(0).box);
  LodSelector sel{r, cam, 480, 0.0};
  // Three leaves whose boxes show; the geometry of the last one does not (behind a wall, its box
  // seen through a window).
  const std::vector<glm::dvec3> boxes_show = {{0.5, 0.5, 0.5}, {9.5, 0.5, 30.5}, {33.5, 0.5, 33.5}};
  GeometryFakeQueries q;
  GeometryGrid() {
    q.h = &h;
    q.visible_points = boxes_show;
    q.geometry_points = {boxes_show[0], boxes_show[1]};
  }
  uint32_t leaf_of(glm::dvec3 p) const {
    for (uint32_t id = 0; id < h.size(); ++id)
      if (h.node(id).leaf() && h.node(id).item_count > 0 && h.node(id).box.contains(p)) return id;
    return kNoNode;
  }
};

}  // namespace

TEST(GeometryQueries, LeafWhoseBoxPassesButGeometryDoesNotIsRejected) {
  GeometryGrid g;
  CullStats box_st, geo_st;
  const auto by_box = hardware_cull_lod(g.h, g.cam, g.q, g.sel, {.stats = &box_st});
  ASSERT_EQ(by_box.size(), 3u);
  EXPECT_TRUE(g.q.tested.empty()) << "box: no geometry queries";
  EXPECT_EQ(box_st.geometry_queries, 0u);
  std::vector<uint32_t> streamed;
  const auto by_geometry = hardware_cull_lod(g.h, g.cam, g.q, g.sel,
                                             {.on_visible = [&](uint32_t id) { streamed.push_back(id); },
                                              .stats = &geo_st,
                                              .leaf_test = LeafTest::geometry});
  const uint32_t hidden = g.leaf_of(g.boxes_show[2]);
  ASSERT_NE(hidden, kNoNode);
  std::vector<uint32_t> expected = by_box;
  std::erase(expected, hidden);
  EXPECT_EQ(by_geometry, expected);
  std::sort(streamed.begin(), streamed.end());
  EXPECT_EQ(streamed, by_geometry) << "a rejected leaf is never streamed";
  EXPECT_EQ(geo_st.geometry_queries, 3u);  // the leaves whose boxes passed, each once
  EXPECT_EQ(geo_st.geometry_occluded, 1u);
  EXPECT_EQ(geo_st.queries, box_st.queries) << "the same box queries";
  std::vector<uint32_t> tested = g.q.tested;
  std::sort(tested.begin(), tested.end());
  EXPECT_EQ(tested, by_box) << "only leaves whose box passed, never interior nodes";
  // Queries without geometry support: the traversal keeps the box's answer.
  FakeQueries plain;
  plain.visible_points = g.boxes_show;
  EXPECT_EQ(hardware_cull_lod(g.h, g.cam, plain, g.sel, {.leaf_test = LeafTest::geometry}), by_box);
}

TEST(GeometryQueries, AreIssuedAfterTheBatchsBoxResultsAndReadBeforeItEnds) {
  GeometryGrid g;
  hardware_cull_lod(g.h, g.cam, g.q, g.sel, {.leaf_test = LeafTest::geometry});
  // Per batch: i..i r..r g..g R..R e.
  std::string order = "irgRe";
  size_t stage = 0, geometry_batches = 0;
  for (char e : g.q.events) {
    const size_t s = order.find(e);
    ASSERT_NE(s, std::string::npos);
    EXPECT_GE(s, stage) << "'" << e << "' after '" << order[stage] << "'";
    if (e == 'g' && stage < 2) ++geometry_batches;
    stage = e == 'e' ? 0 : std::max(stage, s);
  }
  EXPECT_GE(geometry_batches, 1u);
}

TEST(GeometryQueries, TheSkipperLearnsTheFinalResultSoAHiddenLeafIsNeverTrusted) {
  GeometryGrid g;
  const uint32_t hidden = g.leaf_of(g.boxes_show[2]), shown = g.leaf_of(g.boxes_show[0]);
  QuerySkipper skipper(g.h.size());
  CullStats st;
  for (int frame = 0; frame < 12; ++frame) {
    const auto v =
        hardware_cull_lod(g.h, g.cam, g.q, g.sel, {.skipper = &skipper, .stats = &st, .leaf_test = LeafTest::geometry});
    EXPECT_FALSE(std::binary_search(v.begin(), v.end(), hidden)) << "frame " << frame;
    EXPECT_TRUE(std::binary_search(v.begin(), v.end(), shown)) << "frame " << frame;
  }
  EXPECT_GT(st.skipped, 0u) << "leaves whose geometry keeps showing are trusted";
  EXPECT_EQ(st.geometry_occluded, 12u) << "the hidden leaf is tested every frame";
  // Its box passes every time; the skipper was told it was occluded.
  EXPECT_FALSE(skipper.skip(hidden));
}

TEST(GeometryQueries, ALeafHoldingBlendItemsIsAcceptedOnItsBox) {
  GeometryGrid g;
  const uint32_t glassy = g.leaf_of(g.boxes_show[2]);  // its geometry "does not show", but it is glass
  g.q.blended = {glassy};
  CullStats st;
  const auto v = hardware_cull_lod(g.h, g.cam, g.q, g.sel, {.stats = &st, .leaf_test = LeafTest::geometry});
  EXPECT_TRUE(std::binary_search(v.begin(), v.end(), glassy));
  EXPECT_EQ(v.size(), 3u);
  EXPECT_EQ(st.geometry_queries, 2u);
  EXPECT_EQ(st.geometry_occluded, 0u);
}
