// load_gltf / load_scene on the real scenes in ../shared/scenes (skipped when absent): counts match
// the table in scenes/README.md, meshes are valid, missing normals are computed.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <iostream>

#include "common/scene/scene_io.hpp"

using namespace occ;

namespace {

struct SharedScene {
  const char* file;           // under OCC_SHARED_DIR/scenes
  uint64_t readme_triangles;  // "~121k" etc. in scenes/README.md
};

void PrintTo(const SharedScene& s, std::ostream* os) { *os << s.file; }

class SharedScenes : public ::testing::TestWithParam<SharedScene> {};

TEST_P(SharedScenes, LoadsWithPlausibleCountsAndValidMeshes) {
  const std::filesystem::path path = std::filesystem::path(OCC_SHARED_DIR) / "scenes" / GetParam().file;
  if (!std::filesystem::exists(path))
    GTEST_SKIP() << path << " not found (../shared is not beside the checkout)";
  const Scene s = load_scene(path.string());
  std::cout << GetParam().file << ": " << s.objects.size() << " objects, " << s.meshes.size() << " meshes, "
            << s.triangle_count() << " triangles drawn\n";
  EXPECT_EQ(s.source, path.string());
  ASSERT_FALSE(s.objects.empty());
  // README counts the file's triangles; the loader leaves out the zero-area and the repeated ones
  // and says how many.
  EXPECT_NEAR(double(s.triangle_count() + s.zero_area_triangles + s.repeated_triangles),
              double(GetParam().readme_triangles),
              0.05 * GetParam().readme_triangles);
  EXPECT_FALSE(s.bounds().empty());
  for (const Mesh& m : s.meshes) {
    ASSERT_EQ(m.normals.size(), m.positions.size()) << m.name;
    ASSERT_EQ(m.indices.size() % 3, 0u) << m.name;
    ASSERT_GT(m.indices.size(), 0u) << m.name;
    for (uint32_t i : m.indices) ASSERT_LT(i, m.positions.size()) << m.name;
  }
  for (const Object& o : s.objects) ASSERT_LT(o.mesh, s.meshes.size()) << o.name;
}

INSTANTIATE_TEST_SUITE_P(Readme, SharedScenes,
                         ::testing::Values(SharedScene{"2CylinderEngine/2CylinderEngine.gltf", 121000},
                                           SharedScene{"ReciprocatingSaw/ReciprocatingSaw.gltf", 198000},
                                           SharedScene{"duplex/Duplex_A_20110505.gltf", 41000},
                                           SharedScene{"sponza_lod4/sponza_s_lod4.glb", 187000}));

TEST(SharedScenesDetail, InstancingSharesMeshes) {
  const auto path = std::filesystem::path(OCC_SHARED_DIR) / "scenes/2CylinderEngine/2CylinderEngine.gltf";
  if (!std::filesystem::exists(path)) GTEST_SKIP() << path << " not found";
  const Scene s = load_gltf(path.string());
  EXPECT_LT(s.meshes.size(), s.objects.size());  // 34 primitives drawn by 115 (node, primitive) pairs
  std::vector<int> uses(s.meshes.size());
  for (const Object& o : s.objects) ++uses[o.mesh];
  for (int u : uses) EXPECT_GT(u, 0);  // every mesh is drawn
}

TEST(SharedScenesDetail, SponzaIsOneMeshWithComputedUnitNormals) {
  const auto path = std::filesystem::path(OCC_SHARED_DIR) / "scenes/sponza_lod4/sponza_s_lod4.glb";
  if (!std::filesystem::exists(path)) GTEST_SKIP() << path << " not found";
  const Scene s = load_gltf(path.string());
  ASSERT_EQ(s.meshes.size(), 1u);
  ASSERT_EQ(s.objects.size(), 1u);
  size_t unit = 0;
  for (const glm::vec3& n : s.meshes[0].normals) unit += std::abs(glm::length(n) - 1.0f) < 1e-4f;
  EXPECT_EQ(unit, s.meshes[0].normals.size());
}

}  // namespace
