// QueryBudget (culling.hpp): occlusion queries only where they pay, GL-free.
#include <gtest/gtest.h>

#include <algorithm>

#include "common/culling.hpp"
#include "common/scene_io.hpp"

using namespace occ;

namespace {

struct City {
  Scene scene;
  Hierarchy h;
  City() {
    CityParams p;
    p.blocks_x = 4;
    p.blocks_z = 4;
    p.buildings_per_block = 2;
    p.floors_max = 4;
    p.detail = 1;
    scene = generate_city(p);
    h = Hierarchy::build(scene, {});
  }
};

// A box passes when it contains one of the points (a fixed, order-independent oracle).
struct PointQueries : OcclusionQueries {
  std::vector<glm::dvec3> points;
  bool all_visible = false;
  std::vector<uint8_t> results;
  uint32_t issue(const Aabb& box) override {
    bool v = all_visible;
    for (auto& p : points) v |= box.contains(p);
    results.push_back(v);
    return uint32_t(results.size() - 1);
  }
  uint64_t result(uint32_t h) override { return results.at(h) ? 100 : 0; }
  void end_batch() override { results.clear(); }
};

Camera above(const Aabb& b) {
  const glm::dvec3 c = b.center();
  return Camera::look_at(c + glm::dvec3(0, b.diagonal(), b.diagonal() * 0.5), c, {0, 1, 0}, 60, 1.0, 0.5,
                         b.diagonal() * 4);
}

// The city seen from above, an oracle and a budget with the given prices (ms per query and per
// triangle).
struct PricedCity {
  City c;
  Renderables r{c.h, nullptr};
  Camera cam = above(c.h.node(0).box);
  LodSelector sel{r, cam, 512, 0.0};
  PointQueries q;
  QueryBudget budget{c.h};
  PricedCity(double ms_per_query, double ms_per_triangle) { budget.set_costs(ms_per_query, ms_per_triangle); }
  std::vector<uint32_t> cull(CullStats* st = nullptr, bool with_budget = true) {
    return hardware_cull_lod(c.h, cam, q, sel, {.budget = with_budget ? &budget : nullptr, .stats = st});
  }
};

}  // namespace

TEST(QueryBudget, ChildrenHaveLargerIdsThanTheirParents) {  // end_traversal folds upward by id
  const City c;
  for (uint32_t id = 1; id < c.h.size(); ++id) EXPECT_LT(c.h.node(id).parent, id);
}

TEST(QueryBudget, WhereNothingIsOccludedSubtreesAreAcceptedWholeAndNothingVisibleIsLost) {
  PricedCity s(0.05, 1e-5);  // a query costs what 5,000 triangles cost
  s.q.all_visible = true;
  const auto truth = s.cull(nullptr, false);
  ASSERT_GT(truth.size(), 20u);
  uint32_t first_queries = 0, later_queries = 0, wholes = 0;
  for (int f = 0; f < 12; ++f) {
    CullStats st;
    const auto got = s.cull(&st);
    EXPECT_EQ(got, truth) << "frame " << f << ": accepting whole must give every visible leaf, no more here";
    if (f == 0) first_queries = st.queries;
    if (f >= 2) later_queries += st.queries;
    wholes += st.whole;
  }
  EXPECT_GT(wholes, 0u);
  EXPECT_LT(later_queries, first_queries * 10 / 4) << "10 later frames should cost less than 2.5 first frames";
}

TEST(QueryBudget, WhereQueriesCullTheyKeepBeingIssuedAndResultsStayExact) {
  PricedCity s(0.05, 1e-2);  // a query costs what 5 triangles cost: culling pays
  s.q.points = {s.c.h.node(0).box.center()};  // almost everything occluded
  const auto truth = s.cull(nullptr, false);
  for (int f = 0; f < 8; ++f) {
    CullStats st;
    EXPECT_EQ(s.cull(&st), truth) << "frame " << f;
    EXPECT_EQ(st.whole, 0u) << "frame " << f;
  }
  EXPECT_GT(s.budget.subtree_saved_triangles(0), 0u);
  EXPECT_GT(s.budget.subtree_queries(0), 0u);
}

TEST(QueryBudget, AcceptedSubtreesAreTestedAgainAfterTheirWait) {
  PricedCity s(0.05, 1e-2);
  s.q.all_visible = true;
  s.cull();  // figures: nothing occluded
  // Now most of the scene becomes occluded: within the longest wait the budget must test again
  // and stop accepting subtrees whole (conservative meanwhile: a superset of the truth).
  s.q.all_visible = false;
  s.q.points = {s.c.h.node(0).box.center()};
  const auto truth = s.cull(nullptr, false);
  size_t last = 0;
  for (int f = 0; f < 3 * QueryBudget::kMaxWait; ++f) {
    const auto got = s.cull();
    EXPECT_TRUE(std::includes(got.begin(), got.end(), truth.begin(), truth.end())) << "frame " << f;
    last = got.size();
  }
  EXPECT_EQ(last, truth.size());
}
