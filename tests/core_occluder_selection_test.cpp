// OccluderSelection (culling.hpp): which visible objects the OR draws as occluders, GL-free.
#include <gtest/gtest.h>

#include <cmath>

#include "common/culling.hpp"
#include "common/scene_io.hpp"

using namespace occ;

namespace {

constexpr double kH = 512;  // viewport height, pixels

Camera camera_at(const glm::dvec3& eye) {
  return Camera::look_at(eye, eye + glm::dvec3(0, 0, -1), {0, 1, 0}, 60.0, 1.0, 0.1, 1000.0);
}

Aabb unit_box() { return {{-0.5, -0.5, -0.5}, {0.5, 0.5, 0.5}}; }

// The projected sphere's area, computed here from the definition (radius half the diagonal, at
// the box's nearest point, pinhole projection with fovy 60 degrees).
double area_px(double distance) {
  const double r = 0.5 * std::sqrt(3.0) * kH / (2.0 * distance * std::tan(glm::radians(30.0)));
  return std::min(M_PI * r * r, kH * kH);
}

}  // namespace

TEST(OccluderSelection, ZeroKeepsEveryObject) {
  const OccluderSelection all{0.0};
  EXPECT_TRUE(all.worth(unit_box(), 1'000'000'000, camera_at({0, 0, 1e5}), kH));
}

TEST(OccluderSelection, KeepsAnObjectExactlyWhileItCoversEnoughPixelsPerTriangle) {
  const OccluderSelection sel{1.0};
  for (double d : {2.0, 10.0, 50.0, 400.0}) {
    const Camera cam = camera_at({0, 0, 0.5 + d});  // d from the box's near face
    const double a = area_px(d);
    EXPECT_TRUE(sel.worth(unit_box(), uint64_t(std::floor(a * 0.99)), cam, kH)) << d;
    EXPECT_FALSE(sel.worth(unit_box(), uint64_t(std::ceil(a * 1.01)) + 1, cam, kH)) << d;
  }
  // Twice the threshold halves the triangles it accepts.
  const OccluderSelection strict{2.0};
  const Camera cam = camera_at({0, 0, 10.5});
  EXPECT_TRUE(strict.worth(unit_box(), uint64_t(area_px(10) * 0.49), cam, kH));
  EXPECT_FALSE(strict.worth(unit_box(), uint64_t(area_px(10) * 0.51), cam, kH));
}

TEST(OccluderSelection, EyeInOrOnTheBoxAlwaysKeepsIt) {
  const OccluderSelection sel{1e6};
  EXPECT_TRUE(sel.worth(unit_box(), 1'000'000, camera_at({0, 0, 0}), kH));
  EXPECT_TRUE(sel.worth(unit_box(), 1'000'000, camera_at({0, 0, 0.5}), kH));  // on a face
  EXPECT_FALSE(sel.worth(unit_box(), 1'000'000, camera_at({0, 0, 0.6}), kH));
}

TEST(OccluderSelection, AreaIsCappedAtTheViewport) {
  const OccluderSelection sel{1.0};
  const Camera near = camera_at({0, 0, 0.5001});
  EXPECT_TRUE(sel.worth(unit_box(), uint64_t(kH * kH), near, kH));
  EXPECT_FALSE(sel.worth(unit_box(), uint64_t(kH * kH) + 1, near, kH));
}

TEST(OccluderSelection, FilterDropsOnlyDenseSmallObjectsAndKeepsTheOrder) {
  // A city: buildings are low-poly boxes, all worth drawing from a street; from very far away
  // none is, at 1 pixel per triangle.
  CityParams p;
  p.blocks_x = 3;
  p.blocks_z = 3;
  p.buildings_per_block = 2;
  p.floors_max = 3;
  p.detail = 2;
  Scene scene = generate_city(p);
  const Hierarchy h = Hierarchy::build(scene, {});
  const Renderables r(h, nullptr);
  std::vector<uint32_t> leaves;
  for (uint32_t id = 0; id < h.size(); ++id)
    if (h.node(id).leaf() && h.node(id).item_count > 0) leaves.push_back(id);
  ASSERT_GT(leaves.size(), 10u);
  const OccluderSelection sel{1.0};
  const glm::dvec3 c = h.node(0).box.center();
  const double size = h.node(0).box.diagonal();

  std::vector<uint32_t> near_ids = leaves, far_ids = leaves;
  const Camera inside = camera_at(c);
  sel.filter(near_ids, r, inside, kH);
  std::vector<uint32_t> expected;
  for (uint32_t id : leaves)
    if (sel.worth(h.node(id).box, r.triangles(id), inside, kH)) expected.push_back(id);
  EXPECT_EQ(near_ids, expected);
  EXPECT_GT(near_ids.size(), leaves.size() / 2);

  sel.filter(far_ids, r, camera_at(c + glm::dvec3(0, 0, 1e4 * size)), kH);
  EXPECT_TRUE(far_ids.empty());
}
