// The procedural plant (--scene plant:M, common/plant.hpp): deterministic, about M million
// triangles, unique meshes, a walk down its aisle, clear errors for bad specs.
#include <gtest/gtest.h>

#include <iostream>
#include <set>

#include "common/camera_path.hpp"
#include "common/error.hpp"
#include "common/hierarchy.hpp"
#include "common/plant.hpp"
#include "common/scene_io.hpp"
#include "scene_fixtures.hpp"

using namespace occ;

namespace {

using occtest::spec_error;

}  // namespace

TEST(Plant, SameSpecSameFingerprintTwice) {
  Scene a = load_scene("plant:0.3"), b = load_scene("plant:0.3");
  const uint64_t fa = Hierarchy::build(a, {}).fingerprint(), fb = Hierarchy::build(b, {}).fingerprint();
  EXPECT_EQ(fa, fb);
  EXPECT_EQ(a.content_hash(), b.content_hash());
  Scene c = plant::generate_plant({0.3, 2});  // another seed, another plant
  EXPECT_NE(Hierarchy::build(c, {}).fingerprint(), fa);
}

TEST(Plant, TriangleCountWithinTenPercentOfM) {
  for (double m : {0.05, 0.3, 1.0, 2.5}) {
    const Scene s = plant::generate_plant({m, 1});
    const double tris = double(s.triangle_count());
    std::cout << "plant:" << m << ": " << s.objects.size() << " objects, " << tris << " triangles\n";
    EXPECT_GT(tris, 0.9 * m * 1e6) << m;
    EXPECT_LT(tris, 1.1 * m * 1e6) << m;
  }
}

TEST(Plant, EveryObjectHasItsOwnMeshAndPlantLikeSizes) {
  const Scene s = load_scene("plant:1");
  ASSERT_EQ(s.objects.size(), s.meshes.size());
  std::set<uint32_t> used;
  for (const Object& o : s.objects) used.insert(o.mesh);
  EXPECT_EQ(used.size(), s.meshes.size());  // no instancing
  // Thousands of objects, from a dozen triangles (slabs, walls) to thousands (tube bundles).
  EXPECT_GT(s.objects.size(), 1000u);
  EXPECT_LT(s.objects.size(), 20000u);
  uint64_t smallest = UINT64_MAX, largest = 0;
  for (const Mesh& m : s.meshes) {
    smallest = std::min(smallest, m.triangle_count());
    largest = std::max(largest, m.triangle_count());
    EXPECT_EQ(m.normals.size(), m.positions.size());
    for (uint32_t i : m.indices) ASSERT_LT(i, m.positions.size());
  }
  EXPECT_LE(smallest, 12u);
  EXPECT_GE(largest, 2000u);
}

TEST(Plant, WalkGoesDownTheAisleAndTheAisleIsClear) {
  const Scene s = load_scene("plant:1");
  const Aabb bounds = s.bounds();
  EXPECT_NEAR(bounds.min.y, 0.0, 1e-6);  // the walk's eye height is measured from here
  const std::vector<Camera> walk = load_camera_path("walk:40", bounds, Viewport{256, 256});
  ASSERT_EQ(walk.size(), 40u);
  for (const Camera& c : walk) {
    EXPECT_LT(std::abs(c.eye.z), 0.5 * plant::kAisle - 0.5);
    EXPECT_NEAR(c.eye.y, 1.7, 1e-6);
    EXPECT_GT(c.eye.x, bounds.min.x + 1.0);
    EXPECT_LT(c.eye.x, bounds.max.x - 1.0);
  }
  // Between the end walls, nothing in the aisle below kAisleClear but the ground (y = 0): no
  // vertex there (the columns lining it stand 0.3 m back).
  const double x_lo = walk.front().eye.x - 1.0, x_hi = walk.back().eye.x + 1.0;
  size_t crossing = 0;
  for (const Object& o : s.objects) {
    const Aabb box = s.meshes[o.mesh].box().transformed(o.transform);
    if (box.min.z < -0.5 * plant::kAisle && box.max.z > 0.5 * plant::kAisle &&
        box.max.y < plant::kLevelHeight * plant::kLevels && o.name.rfind("pipe", 0) == 0)
      ++crossing;  // a pipe across the aisle
    for (const glm::vec3& v : s.meshes[o.mesh].positions) {
      const glm::dvec3 p = glm::dvec3(o.transform * glm::dvec4(glm::dvec3(v), 1.0));
      if (p.x < x_lo || p.x > x_hi || std::abs(p.z) > 0.5 * plant::kAisle - 0.3) continue;
      if (p.y > plant::kAisleClear) continue;
      ASSERT_LT(std::abs(p.y), 1e-4) << o.name << " has a vertex in the aisle at " << p.x << ", " << p.y << ", "
                                     << p.z;
    }
  }
  EXPECT_GT(crossing, 0u);  // pipes cross the aisle overhead (depth complexity above the walk)
}

TEST(Plant, BadSpecsNameTheSpec) {
  for (const char* spec : {"plant:0", "plant:500", "plant:x", "plant:", "plant:-1", "plant:nan", "plant:1x"}) {
    const std::string e = spec_error(spec);
    EXPECT_NE(e.find(std::string("'") + spec + "'"), std::string::npos) << spec << ": " << e;
    EXPECT_NE(e.find("0.01..200"), std::string::npos) << e;
  }
  EXPECT_THROW(plant::generate_plant({0.0, 1}), InputError);
}
