// The hard-case scene generator (common/scene/scene_io.hpp: hard:walls, hard:span, hard:degenerate,
// offset:DX,DY,DZ:<spec>): deterministic, the documented geometry, translations exact in double,
// bad specs named.
#include <gtest/gtest.h>

#include "common/error.hpp"
#include "common/scene/scene_io.hpp"

using namespace occ;

TEST(HardScenes, GeneratedScenesAreDeterministic) {
  for (const char* spec : {"hard:walls", "hard:walls:3", "hard:span", "hard:degenerate", "hard:cracks", "hard:cracks:5",
                           "offset:1e7,-2,3.5:hard:span"})
    EXPECT_EQ(load_scene(spec).content_hash(), load_scene(spec).content_hash()) << spec;
}

TEST(HardScenes, WallsHaveZeroThicknessBoxes) {
  const Scene s = load_scene("hard:walls:2");
  int flat = 0;
  for (const Object& o : s.objects) {
    const Aabb b = s.meshes[o.mesh].box().transformed(o.transform);
    flat += b.min.x == b.max.x || b.min.y == b.max.y || b.min.z == b.max.z;
  }
  EXPECT_EQ(flat, 4);  // ground, edge-on wall, 2 walls
  EXPECT_EQ(s.bounds().min, glm::dvec3(-20, 0, -20));
}

TEST(HardScenes, SpanCoversOneThousandthToOneHundredThousand) {
  const Scene s = load_scene("hard:span");
  double smallest = 1e300;
  for (const Object& o : s.objects) {
    const Aabb b = s.meshes[o.mesh].box().transformed(o.transform);
    smallest = std::min(smallest, std::max({b.extent().x, b.extent().y, b.extent().z}));
  }
  EXPECT_NEAR(smallest, 1e-3, 1e-9);
  EXPECT_NEAR(s.bounds().extent().x, 1e5, 1e-6);
}

TEST(HardScenes, DegenerateSceneKeepsItsZeroAreaTriangles) {
  const Scene s = load_scene("hard:degenerate");
  int zero_area = 0;
  for (const Mesh& m : s.meshes)
    for (size_t t = 0; t + 2 < m.indices.size(); t += 3) {
      const glm::vec3 a = m.positions[m.indices[t]], b = m.positions[m.indices[t + 1]], c = m.positions[m.indices[t + 2]];
      zero_area += glm::length(glm::cross(b - a, c - a)) == 0.0f;
    }
  EXPECT_GE(zero_area, 9);
}

TEST(HardScenes, OffsetTranslatesExactlyInDouble) {
  const Scene base = load_scene("hard:walls"), moved = load_scene("offset:1e7,-1e6,0.25:hard:walls");
  ASSERT_EQ(base.objects.size(), moved.objects.size());
  EXPECT_EQ(moved.bounds().min, base.bounds().min + glm::dvec3(1e7, -1e6, 0.25));
  EXPECT_EQ(moved.bounds().max, base.bounds().max + glm::dvec3(1e7, -1e6, 0.25));
  EXPECT_EQ(moved.source, "offset:1e7,-1e6,0.25:hard:walls");
}

TEST(HardScenes, BadSpecsAreNamed) {
  auto message = [](const std::string& spec) {
    try {
      load_scene(spec);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_NE(message("hard:nope").find("unknown hard case"), std::string::npos);
  EXPECT_NE(message("hard:walls:0").find("walls must be 1..100"), std::string::npos);
  EXPECT_NE(message("hard:span:3").find("unknown hard case"), std::string::npos);
  EXPECT_NE(message("hard:cracks:0").find("bays must be 1..50"), std::string::npos);
  EXPECT_NE(message("offset:1,2:hard:walls").find("offset must be DX,DY,DZ"), std::string::npos);
  EXPECT_NE(message("offset:1,2,x:hard:walls").find("'x' must be a finite number"), std::string::npos);
  EXPECT_NE(message("offset:1,2,inf:hard:walls").find("must be a finite number"), std::string::npos);
  EXPECT_NE(message("offset:2e9,0,0:hard:walls").find("|v| <= 1e9"), std::string::npos);
  EXPECT_NE(message("offset:1,2,3").find("expected offset:DX,DY,DZ:<scene spec>"), std::string::npos);
  EXPECT_NE(message("offset:1,2,3:hard:nope").find("unknown hard case"), std::string::npos);
}

// hard:cracks: seams of 0 .. 24 mm between the cross walls' panels (bays 0..3: 0, 0.5, 2, 8 mm
// times 1, 2, 3), every part its own mesh, and objects of 2 to 10 mm behind the seams.
TEST(HardScenes, CracksHaveSeamsOfTheStatedWidthsBetweenSeparateMeshes) {
  const Scene s = load_scene("hard:cracks:4");
  std::vector<double> seams;  // gaps along z between consecutive cross wall panels at y = 0.5
  std::vector<Aabb> panels;
  int tiny = 0;
  for (const Object& o : s.objects) {
    const Aabb b = s.meshes[o.mesh].box().transformed(o.transform);
    if (o.name.find("cross wall panel") != std::string::npos && b.min.y < 0.5 && b.max.y > 0.5) panels.push_back(b);
    tiny += b.max.x - b.min.x <= 0.0101;
  }
  ASSERT_EQ(panels.size(), 16u);  // 4 bays x 4 panels
  for (size_t i = 0; i + 1 < panels.size(); ++i)
    if (panels[i].min.x == panels[i + 1].min.x) seams.push_back(panels[i + 1].min.z - panels[i].max.z);
  ASSERT_EQ(seams.size(), 12u);
  const double base[4] = {0.0, 0.0005, 0.002, 0.008};
  for (size_t k = 0; k < 4; ++k)
    for (size_t j = 0; j < 3; ++j) EXPECT_NEAR(seams[3 * k + j], base[k] * double(j + 1), 1e-6) << k << " " << j;
  EXPECT_EQ(tiny, 4 * (9 + 36));  // behind the seams, and the floor's field
  EXPECT_EQ(s.meshes.size(), 1u + 4 * 10);  // the cube, and each of a bay's 10 parts its own mesh
}

// The limit benchmarks' structures (common/scene/structures.hpp): deterministic, their size set
// by N, each object's geometry where the layout says, bad specs named.
TEST(Structures, GeneratedDeterministicallyAndSizedByN) {
  for (const char* kind : {"bridge", "office", "pipes"}) {
    const std::string one = std::string(kind) + ":1", four = std::string(kind) + ":4";
    EXPECT_EQ(load_scene(one).content_hash(), load_scene(one).content_hash()) << kind;
    const size_t a = load_scene(one).objects.size(), b = load_scene(four).objects.size();
    EXPECT_GT(b, 3 * a) << kind;  // N spans, bays or modules, beside what is shared (ground, end walls)
    EXPECT_EQ(load_scene(kind).objects.size(), load_scene(std::string(kind) + (kind[0] == 'p' ? ":24" : ":16")).objects.size());
  }
  const Scene office = load_scene("office:2");
  EXPECT_NEAR(office.bounds().extent().x, 12.4, 1e-9);  // two 6 m bays, end walls to 0.25 before, 0.15 beyond
  EXPECT_EQ(office.bounds().min.y, -0.2);
  uint32_t glass = 0;
  for (const Object& o : load_scene("office:4").objects) glass += office.material_of(o.mesh) != nullptr;
  EXPECT_GT(glass, 0u);  // window bands and the third cross wall
}

TEST(Structures, BadSpecsAreNamed) {
  for (const char* spec : {"bridge:0", "bridge:201", "office:x", "pipes:101", "bridge:2:3", "office:"}) {
    try {
      load_scene(spec);
      ADD_FAILURE() << spec << " was accepted";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(std::string("'") + spec + "'"), std::string::npos) << e.what();
    }
  }
}
