// Front tracking (front.hpp) and the LOD-aware HC traversal against brute force (no GL).
#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include "common/cull/culling.hpp"
#include "common/cull/front.hpp"
#include "common/scene/scene_io.hpp"
#include "protocol/cluster/switch_step.hpp"
#include "scene_fixtures.hpp"

using namespace occ;

namespace {

struct World {
  Scene scene;
  Hierarchy h;
  LodData lod;
};

const World& world() {
  static World* w = [] {
    auto* w = new World;
    w->scene = generate_city(occtest::city_params(4, 3, 2, 8, 1));
    BuildParams bp;
    bp.arity = 4;
    bp.cluster_triangles = 128;
    w->h = Hierarchy::build(w->scene, bp);
    w->lod = LodData::build(w->scene, w->h, {});
    return w;
  }();
  return *w;
}

Camera random_camera(std::mt19937& rng, const Aabb& b) {
  std::uniform_real_distribution<double> u(0, 1);
  const glm::dvec3 e = b.extent();
  glm::dvec3 eye = b.min - 0.2 * e + glm::dvec3(u(rng) * 1.4 * e.x, 1.7 + u(rng) * e.y * 2, u(rng) * 1.4 * e.z);
  glm::dvec3 target = b.min + glm::dvec3(u(rng) * e.x, u(rng) * e.y, u(rng) * e.z);
  if (glm::length(target - eye) < 1) target = eye + glm::dvec3(1, 0, 0);
  return Camera::look_at(eye, target, {0, 1, 0}, 40 + 50 * u(rng), 4.0 / 3.0, 0.1, 1e4);
}

// Each non-empty leaf has exactly one ancestor-or-self in `cut`.
void expect_covers_once(const Hierarchy& h, const std::vector<uint32_t>& cut) {
  std::vector<uint8_t> in(h.size(), 0);
  for (uint32_t c : cut) in[c] = 1;
  for (uint32_t id = 0; id < h.size(); ++id) {
    if (!h.node(id).leaf() || h.node(id).item_count == 0) continue;
    int n = 0;
    for (uint32_t a = id; a != kNoNode; a = h.node(a).parent) n += in[a];
    EXPECT_EQ(n, 1) << "leaf " << id;
  }
}

// Monotone fake occlusion: a box shows as many samples as visible points it contains (a child's
// box is inside its parent's, so a parent is never occluded when a child shows).
struct PointQueries : OcclusionQueries {
  std::vector<glm::dvec3> points;
  std::vector<Aabb> boxes;
  uint32_t issue(const Aabb& b) override {
    boxes.push_back(b);
    return uint32_t(boxes.size() - 1);
  }
  uint64_t result(uint32_t handle) override {
    uint64_t n = 0;
    for (auto& p : points) n += boxes[handle].contains(p);
    return n;
  }
  void end_batch() override { boxes.clear(); }
};

std::vector<glm::dvec3> random_points(std::mt19937& rng, const Aabb& b, int n);

// A random view of the world: `n` visible points (the oracle) and a camera.
struct RandomView {
  PointQueries q;
  Camera cam;
  RandomView(std::mt19937& rng, const Aabb& world, int n) {
    q.points = random_points(rng, world, n);
    cam = random_camera(rng, world);
  }
};

std::vector<glm::dvec3> random_points(std::mt19937& rng, const Aabb& b, int n) {
  std::uniform_real_distribution<double> u(0, 1);
  std::vector<glm::dvec3> pts;
  for (int i = 0; i < n; ++i) {
    const glm::dvec3 e = b.extent();
    pts.push_back(b.min + glm::dvec3(u(rng) * e.x, u(rng) * e.y, u(rng) * e.z));
  }
  return pts;
}

// `views` random views of the world from `seed`, view k with 1 + k % most_points visible points:
// check(k, its camera, its occlusion oracle) for each.
template <class Check>
void for_random_views(unsigned seed, int views, int most_points, Check check) {
  std::mt19937 rng(seed);
  for (int k = 0; k < views; ++k) {
    RandomView view(rng, world().h.node(0).box, 1 + k % most_points);
    check(k, view.cam, view.q);
  }
}

}  // namespace

TEST(Front, UpdatedCutEqualsFreshCutOnRandomCameras) {
  const World& w = world();
  Renderables r(w.h, &w.lod);
  std::mt19937 rng(1);
  int changed = 0, coarsened = 0;
  for (int k = 0; k < 300; ++k) {
    const double tau = std::vector<double>{0, 1, 5, 20, 50, 100, 300}[k % 7];
    LodSelector a(r, random_camera(rng, w.h.node(0).box), 480, tau);
    LodSelector b(r, random_camera(rng, w.h.node(0).box), 480, k % 5 == 0 ? tau * 3 : tau);
    const std::vector<uint32_t> cut_a = lod_cut(w.h, a), fresh_b = lod_cut(w.h, b);
    expect_covers_once(w.h, cut_a);
    const std::vector<uint32_t> updated = update_cut(w.h, b, cut_a);
    ASSERT_EQ(updated, fresh_b) << "camera pair " << k << " tau " << tau;
    changed += cut_a != fresh_b;
    for (uint32_t n : cut_a) coarsened += !std::binary_search(fresh_b.begin(), fresh_b.end(), n) && b.satisfies(n);
    // States after the update: every node refined (satisfies, parent does not).
    for (uint32_t n : updated) {
      EXPECT_TRUE(b.satisfies(n));
      if (w.h.node(n).parent != kNoNode) { EXPECT_FALSE(b.satisfies(w.h.node(n).parent)); }
    }
  }
  EXPECT_GT(changed, 50);   // the cameras did move the cut ...
  EXPECT_GT(coarsened, 0);  // ... in both directions
  std::printf("cut changed on %d of 300 camera pairs; %d over-refined nodes coarsened\n", changed, coarsened);
}

TEST(Front, TauZeroCutIsAllLeaves) {
  const World& w = world();
  Renderables r(w.h, &w.lod);
  std::mt19937 rng(2);
  LodSelector sel(r, random_camera(rng, w.h.node(0).box), 480, 0.0);
  std::vector<uint32_t> leaves;
  for (uint32_t id = 0; id < w.h.size(); ++id)
    if (w.h.node(id).leaf() && w.h.node(id).item_count > 0) leaves.push_back(id);
  EXPECT_EQ(lod_cut(w.h, sel), leaves);
}

TEST(Front, CoarsenedVisibleFrontHasNoOverRefinedNodes) {
  const World& w = world();
  Renderables r(w.h, &w.lod);
  std::mt19937 rng(3);
  for (int k = 0; k < 100; ++k) {
    const double tau = 1.0 + k % 10;
    LodSelector a(r, random_camera(rng, w.h.node(0).box), 480, tau);
    LodSelector b(r, random_camera(rng, w.h.node(0).box), 480, tau);
    // A visible front: a random half of camera a's cut, as renderables.
    std::vector<uint32_t> v;
    for (uint32_t n : lod_cut(w.h, a))
      if (rng() % 2) v.push_back(a.renderable(n));
    const std::vector<uint32_t> c = coarsen_visible(b, v);
    std::vector<uint32_t> nodes = nodes_of(r, c);
    EXPECT_EQ(nodes.size(), c.size());  // one representation per node
    for (uint32_t x : c) {
      const uint32_t n = r.node_of(x);
      if (w.h.node(n).parent != kNoNode) { EXPECT_FALSE(b.satisfies(w.h.node(n).parent)) << "over-refined " << n; }
      if (w.h.node(n).leaf()) { EXPECT_GE(r.level_of(x), b.leaf_level(n)); }
    }
    // Every input node is inside exactly one output node (antichain, nothing lost).
    for (uint32_t x : v) {
      int inside = 0;
      for (uint32_t a2 = r.node_of(x); a2 != kNoNode; a2 = w.h.node(a2).parent)
        inside += std::binary_search(nodes.begin(), nodes.end(), a2);
      EXPECT_EQ(inside, 1);
    }
    // Coarsening twice changes nothing.
    EXPECT_EQ(coarsen_visible(b, c), c);
  }
}

TEST(Front, DerivedOccludedFrontCompletesTheCut) {
  const World& w = world();
  Renderables r(w.h, &w.lod);
  std::mt19937 rng(4);
  EXPECT_EQ(derive_occluded_front(w.h, {}), std::vector<uint32_t>{0});
  for (int k = 0; k < 100; ++k) {
    LodSelector a(r, random_camera(rng, w.h.node(0).box), 480, double(k % 6));
    std::vector<uint32_t> v;
    for (uint32_t n : lod_cut(w.h, a))
      if (rng() % 3 == 0) v.push_back(n);
    std::vector<uint32_t> above;
    std::vector<uint32_t> o = derive_occluded_front(w.h, v, &above);
    std::vector<uint32_t> cut = o;
    cut.insert(cut.end(), v.begin(), v.end());
    std::sort(cut.begin(), cut.end());
    EXPECT_EQ(std::adjacent_find(cut.begin(), cut.end()), cut.end());  // disjoint
    expect_covers_once(w.h, cut);
    for (uint32_t x : above) EXPECT_FALSE(w.h.node(x).leaf());
  }
}

TEST(FrontCull, TauZeroLodTraversalEqualsHardwareCull) {
  const World& w = world();
  Renderables r(w.h, &w.lod);
  for_random_views(5, 50, 20, [&](int, const Camera& cam, PointQueries& q) {
    LodSelector sel(r, cam, 480, 0.0);
    auto plain = hardware_cull(w.h, cam, q, nullptr);
    auto lod = hardware_cull_lod(w.h, cam, q, sel, {.visible_pixel_lod = true});
    EXPECT_EQ(lod, plain);
  });
}

// The switch step itself (SwitchStep, what the nodes and the render client run), frame after
// frame: V_{f-1} -> coarsen -> fronts -> traversal, against a fresh root traversal of the same
// frame. With a monotone occlusion oracle and visible-pixel LOD off the two must agree exactly,
// for tau = 0 and tau > 0, and the front must save queries. The stream it sends, applied by a
// receiver that coarsens with its own SwitchStep (the OR node, the render client), rebuilds V_f
// with matching set and front hashes.
TEST(FrontCull, FrontTrackedTraversalEqualsFreshTraversal) {
  const World& w = world();
  Renderables r(w.h, &w.lod);
  for (double tau : {0.0, 1.0, 5.0}) {
    std::mt19937 rng(6 + int(tau));
    ClusterConfig config;
    config.pixel_error = tau;
    const SwitchStep hc_step(r, config, 480), receiver_step(r, config, 480);
    ASSERT_TRUE(hc_step.tracking());
    VisibleSet visible(r.count()), received(r.count());  // V_{f-1} on the HC node and on a receiver
    std::vector<wire::Message> stream;
    DiffSender out(7, [&](const wire::Message& m) { stream.push_back(m); });
    DiffReceiver in;
    uint64_t fresh_queries = 0, front_queries = 0;
    Camera cam = random_camera(rng, w.h.node(0).box);
    std::vector<glm::dvec3> points = random_points(rng, w.h.node(0).box, 30);
    for (uint32_t f = 0; f < 60; ++f) {
      // A coherent path: small moves, occasional jumps; a few visible points change.
      if (f % 15 == 14) cam = random_camera(rng, w.h.node(0).box);
      else cam.eye += glm::dvec3(0.7, 0, 0.4);
      points[rng() % points.size()] = random_points(rng, w.h.node(0).box, 1)[0];
      PointQueries q;
      q.points = points;
      const LodSelector sel = config.lod_policy(480).selector(r, cam);
      CullStats fresh_st;
      auto fresh = hardware_cull_lod(w.h, cam, q, sel, {.stats = &fresh_st});
      stream.clear();
      const HcFrame hc = hc_step.hc(f, visible, cam, q, {}, out);
      std::vector<uint32_t> tracked(visible.ids().begin(), visible.ids().end());
      std::sort(tracked.begin(), tracked.end());
      ASSERT_EQ(tracked, fresh) << "tau " << tau << " frame " << f;
      fresh_queries += fresh_st.queries;
      front_queries += hc.stats.queries;
      // The receiving end.
      const uint64_t front = receiver_step.coarsen(received, cam);
      EXPECT_EQ(front, hc.eof.front_hash) << "frame " << f;
      for (const wire::Message& m : stream) ASSERT_FALSE(in.on_diff(received, std::get<wire::NodeDiff>(m)));
      ASSERT_FALSE(in.on_end_of_frame(received, hc.eof)) << "frame " << f;
      EXPECT_TRUE(received == visible);
    }
    EXPECT_GT(fresh_queries, 0u);
    EXPECT_LT(front_queries, fresh_queries) << "tau " << tau;
  }
}

// The occluder hook as the traversal calls it down (OcclusionQueries::occluders_found): the
// renderables offered, and how many times.
struct OfferedQueries final : OcclusionQueries {
  explicit OfferedQueries(OcclusionQueries& q) : q(q) {}
  uint32_t issue(const Aabb& box) override { return q.issue(box); }
  uint64_t result(uint32_t handle) override { return q.result(handle); }
  void end_batch() override { q.end_batch(); }
  void occluders_found(std::span<const uint32_t> ids) override {
    ++calls;
    offered.insert(offered.end(), ids.begin(), ids.end());
  }
  OcclusionQueries& q;
  std::vector<uint32_t> offered;
  size_t calls = 0;
};

// Near-first shells find exactly what whole-frontier batches (a level at a time) find when the
// occlusion oracle does not change (no fusion), and hand every accepted renderable to the
// occluder hook once, shell after shell, before the next shell's queries.
TEST(FrontCull, NearFirstShellsFindTheSameSetAndOfferEachOccluderOnce) {
  const World& w = world();
  Renderables r(w.h, &w.lod);
  for_random_views(12, 30, 25, [&](int k, const Camera& cam, PointQueries& q) {
    const LodSelector sel(r, cam, 480, k % 3 == 0 ? 2.0 : 0.0);
    CullStats lv, nf;
    const auto by_level = hardware_cull_lod(w.h, cam, q, sel,
                                            {.choices = {.occluder_fusion = false},
                                             .stats = &lv,
                                             .first_batch = HcOptions::kWholeFrontier,
                                             .max_batch = HcOptions::kWholeFrontier});
    OfferedQueries hook(q);
    const auto near_first = hardware_cull_lod(w.h, cam, hook, sel, {.stats = &nf});
    EXPECT_EQ(near_first, by_level) << "camera " << k;
    std::sort(hook.offered.begin(), hook.offered.end());
    EXPECT_EQ(hook.offered, near_first) << "camera " << k;
    EXPECT_EQ(nf.queries, lv.queries) << "the same nodes are tested, in another order";
    if (near_first.size() > 4) { EXPECT_GT(hook.calls, 1u) << "shells, not one batch"; }
    EXPECT_GE(nf.levels, lv.levels) << "shells are no larger than the whole frontier";
  });
}

TEST(FrontCull, VisiblePixelLodStopsWhereFewPixelsShow) {
  const World& w = world();
  Renderables r(w.h, &w.lod);
  std::mt19937 rng(9);
  int stops = 0;
  for (int k = 0; k < 30; ++k) {
    PointQueries q;
    q.points = random_points(rng, w.h.node(0).box, 3);  // few "pixels" per box
    const Camera cam = random_camera(rng, w.h.node(0).box);
    LodSelector sel(r, cam, 480, 10.0);
    CullStats on_st, off_st;
    auto on = hardware_cull_lod(w.h, cam, q, sel, {.visible_pixel_lod = true, .stats = &on_st});
    auto off = hardware_cull_lod(w.h, cam, q, sel, {.stats = &off_st});
    EXPECT_LE(on_st.queries, off_st.queries);
    stops += on_st.pixel_stops;
    // Every accepted node: visible, and either within tau or it had fewer than tau samples.
    for (uint32_t x : on) {
      const uint32_t n = r.node_of(x);
      EXPECT_GT(q.result(q.issue(w.h.node(n).box)) + visible_without_query(w.h.node(n).box, cam), 0u);
    }
  }
  EXPECT_GT(stops, 0);
}

// The visibility hold (culling.hpp VisibilityHold), the window itself: a node seen in frame s is
// kept through frame s + K, in the frustum only, and never beside its own ancestor or descendant.
TEST(VisibilityHold, KeepsRecentlySeenNodesInTheFrustumAndNeverOverlapsFound) {
  const World& w = world();
  Renderables r(w.h, &w.lod);
  const Hierarchy& h = w.h;
  const Camera all = Camera::look_at(h.node(0).box.center() + glm::dvec3(0, h.node(0).box.diagonal(), 0.01),
                                     h.node(0).box.center(), {0, 1, 0}, 90, 1, 0.1, 1e5);
  uint32_t leaf = 0, sibling = kNoNode;
  while (!h.node(leaf).leaf()) leaf = h.node(leaf).first_child;
  const uint32_t parent = h.node(leaf).parent;
  for (uint32_t c = h.node(parent).first_child; c < h.node(parent).first_child + h.node(parent).child_count; ++c)
    if (c != leaf && h.node(c).item_count > 0) sibling = c;
  ASSERT_NE(sibling, kNoNode);
  VisibilityHold hold(h.size(), 4);
  const std::vector<uint32_t> prev{leaf, sibling};
  EXPECT_TRUE(hold.held(r, all, prev, {}, 1).empty()) << "never seen: not held";
  hold.seen(leaf, 3);
  hold.seen(sibling, 3);
  EXPECT_TRUE(hold.held(r, all, prev, {}, 4).empty()) << "seen in one frame only: not held";
  hold.seen(leaf, 1);  // an older sighting changes nothing
  EXPECT_TRUE(hold.held(r, all, prev, {}, 4).empty());
  hold.seen(leaf, 3);
  EXPECT_TRUE(hold.held(r, all, prev, {}, 4).empty()) << "the same frame twice is one sighting";
  VisibilityHold late(h.size(), 4);
  late.seen(leaf, 1);
  late.seen(leaf, 20);
  EXPECT_TRUE(late.held(r, all, prev, {}, 21).empty()) << "the sighting before was 19 frames earlier (> 4 K)";
  hold = VisibilityHold(h.size(), 4);
  for (uint32_t f : {1u, 3u}) {
    hold.seen(leaf, f);
    hold.seen(sibling, f);
  }
  EXPECT_EQ(hold.held(r, all, prev, {}, 7), prev) << "seen in frames 1 and 3, K = 4: kept through frame 7";
  EXPECT_TRUE(hold.held(r, all, prev, {}, 8).empty()) << "frame 8: five frames after the last sighting";
  const std::vector<uint32_t> found_leaf{leaf}, found_parent{parent};
  EXPECT_EQ(hold.held(r, all, prev, found_leaf, 5), std::vector<uint32_t>{sibling}) << "found ids are not held twice";
  EXPECT_TRUE(hold.held(r, all, prev, found_parent, 5).empty()) << "the parent's HLOD replaces its children";
  hold.seen(parent, 4);
  hold.seen(parent, 5);
  EXPECT_TRUE(hold.held(r, all, found_parent, found_leaf, 6).empty()) << "a child found: its ancestor is not held";
  // Looking away from the node: outside the frustum, not held.
  const glm::dvec3 c = h.node(leaf).box.center();
  const Camera away = Camera::look_at(c + glm::dvec3(0, 0, 50), c + glm::dvec3(0, 0, 100), {0, 1, 0}, 60, 1, 0.1, 1e4);
  EXPECT_TRUE(hold.held(r, away, std::vector<uint32_t>{leaf}, {}, 6).empty());
  VisibilityHold off(h.size(), 0);
  off.seen(leaf, 2);
  off.seen(leaf, 3);
  EXPECT_TRUE(off.held(r, all, prev, {}, 3).empty()) << "K = 0 is off";
}

// Two switch nodes alternating HC frames, each with its own hold that records its own results and
// the other node's additions (as switch_node does), under an occlusion oracle where some points
// flicker (visible every other frame): V_f always contains the fresh traversal's set, every extra
// id was in V_{f-1} and seen within K frames, V_f stays an antichain (each leaf drawn at most once),
// receivers rebuild it with matching hashes, and far fewer ids cross the wire than without a hold.
TEST(VisibilityHold, TwoNodesKeepFlickeringNodesConservativelyAndSendFewerIds) {
  const World& w = world();
  Renderables r(w.h, &w.lod);
  const Hierarchy& h = w.h;
  constexpr uint32_t K = 6;
  for (double tau : {0.0, 2.0}) {
    uint64_t ids_sent[2] = {0, 0};
    for (int with_hold = 0; with_hold < 2; ++with_hold) {
      std::mt19937 rng(31 + int(tau));
      ClusterConfig config;
      config.pixel_error = tau;
      const SwitchStep step(r, config, 480);
      std::vector<VisibilityHold> holds(2, VisibilityHold(h.size(), with_hold ? K : 0));
      std::vector<uint32_t> last_seen_any(h.size(), 0);  // frame + 1, over both nodes
      VisibleSet visible(r.count()), received(r.count());
      std::vector<wire::Message> stream;
      DiffSender out(64, [&](const wire::Message& m) { stream.push_back(m); });
      DiffReceiver in;
      const Aabb box = h.node(0).box;
      Camera cam = random_camera(rng, box);
      const std::vector<glm::dvec3> steady = random_points(rng, box, 40), flicker = random_points(rng, box, 40);
      for (uint32_t f = 0; f < 96; ++f) {
        if (f % 32 == 31) cam = random_camera(rng, box);
        else cam.eye += glm::dvec3(0.1, 0, 0.05);
        PointQueries q;
        q.points = steady;
        // Half the flickering points show every other frame throughout, half stop after frame 40.
        if (f % 2 == 0) q.points.insert(q.points.end(), flicker.begin(), flicker.begin() + (f < 40 ? 40 : 20));
        const LodSelector sel = config.lod_policy(480).selector(r, cam);
        auto fresh = hardware_cull_lod(h, cam, q, sel);
        for (uint32_t id : fresh) last_seen_any[r.node_of(id)] = f + 1;
        const uint32_t k = f % 2;
        stream.clear();
        VisibleSet before = visible;
        step.coarsen(before, cam);
        const HcFrame hc = step.hc(f, visible, cam, q, {}, out, &holds[k]);
        ids_sent[with_hold] += hc.eof.total_added + hc.eof.total_removed;
        for (const wire::Message& m : stream)
          for (uint32_t id : std::get<wire::NodeDiff>(m).added) holds[1 - k].seen(r.node_of(id), f);
        std::vector<uint32_t> v(visible.ids().begin(), visible.ids().end());
        std::sort(v.begin(), v.end());
        ASSERT_TRUE(std::includes(v.begin(), v.end(), fresh.begin(), fresh.end())) << "tau " << tau << " frame " << f;
        if (!with_hold) { EXPECT_EQ(v, fresh); }
        EXPECT_EQ(hc.held, v.size() - fresh.size());
        std::vector<uint8_t> in_v(h.size(), 0);
        for (uint32_t id : v) {
          const uint32_t n = r.node_of(id);
          ASSERT_EQ(in_v[n], 0) << "node " << n << " twice in V";
          in_v[n] = 1;
          if (!std::binary_search(fresh.begin(), fresh.end(), id)) {
            EXPECT_TRUE(before.contains(id)) << "held ids come from V_{f-1}";
            EXPECT_GE(last_seen_any[n] + K, f + 1) << "held longer than K frames: node " << n;
            EXPECT_NE(cam.frustum().classify(h.node(n).box), Containment::Outside);
          }
        }
        for (uint32_t id = 0; id < h.size(); ++id) {  // each leaf drawn at most once
          if (!h.node(id).leaf()) continue;
          int n = 0;
          for (uint32_t a = id; a != kNoNode; a = h.node(a).parent) n += in_v[a];
          ASSERT_LE(n, 1) << "leaf " << id << " under two nodes of V, frame " << f;
        }
        // The receiving end rebuilds V_f.
        const uint64_t front = step.coarsen(received, cam);
        EXPECT_EQ(front, hc.eof.front_hash);
        for (const wire::Message& m : stream) ASSERT_FALSE(in.on_diff(received, std::get<wire::NodeDiff>(m)));
        ASSERT_FALSE(in.on_end_of_frame(received, hc.eof)) << "frame " << f;
        EXPECT_TRUE(received == visible);
      }
    }
    std::printf("tau %g: ids sent %llu with the hold, %llu without\n", tau, (unsigned long long)ids_sent[1],
                (unsigned long long)ids_sent[0]);
    EXPECT_LT(2 * ids_sent[1], ids_sent[0]) << "tau " << tau << ": with hold " << ids_sent[1] << " ids, without "
                                            << ids_sent[0];
  }
}
