// generate_city, layout_grid and the --scene spec parser (no files needed).
#include <gtest/gtest.h>

#include <cstdio>
#include <glm/gtc/matrix_transform.hpp>
#include <iostream>

#include "common/scene/city.hpp"
#include "common/error.hpp"
#include "common/scene/scene_io.hpp"
#include "scene_fixtures.hpp"

using namespace occ;

namespace {

CityParams small_city(int detail = 1) { return occtest::city_params(3, 2, 3, 6, detail); }

using occtest::spec_error;

}  // namespace

TEST(City, DeterministicForASeed) {
  const Scene a = generate_city(small_city()), b = generate_city(small_city());
  EXPECT_EQ(a.content_hash(), b.content_hash());
  CityParams other = small_city();
  other.seed = 2;
  EXPECT_NE(generate_city(other).content_hash(), a.content_hash());
}

TEST(City, DefaultAndLargeSpecTriangleCounts) {
  const Scene city = load_scene("city");
  std::cout << "city: " << city.objects.size() << " objects, " << city.meshes.size() << " meshes, "
            << city.triangle_count() << " triangles\n";
  EXPECT_EQ(city.content_hash(), generate_city(CityParams{}).content_hash());
  EXPECT_EQ(city.objects.size(), 10u * 10u * (1 + 4 * 4));
  EXPECT_GT(city.triangle_count(), 300'000u);
  EXPECT_LT(city.triangle_count(), 800'000u);
  EXPECT_LT(city.meshes.size(), city.objects.size() / 2);  // buildings of equal size share meshes

  const Scene big = load_scene("city:20x20:4:16:2");  // the >= 2M spec documented in scene_io.cpp
  std::cout << "city:20x20:4:16:2: " << big.objects.size() << " objects, " << big.triangle_count()
            << " triangles\n";
  EXPECT_GE(big.triangle_count(), 2'000'000u);
}

TEST(City, TrianglesGrowWithDetailSquared) {
  const uint64_t t1 = generate_city(small_city(1)).triangle_count();
  const uint64_t t2 = generate_city(small_city(2)).triangle_count();
  const uint64_t t3 = generate_city(small_city(3)).triangle_count();
  EXPECT_GT(t2, 3 * t1);  // facades x4, roofs and ground constant
  EXPECT_GT(t3, 2 * t2);
}

TEST(City, BuildingsStayInTheirBlocksAndLotsOffTheStreets) {
  const CityParams p = small_city();
  const Scene s = generate_city(p);
  int buildings = 0;
  for (const Object& o : s.objects) {
    int i, j, k;
    if (std::sscanf(o.name.c_str(), "block %d,%d building %d", &i, &j, &k) != 3) continue;
    ++buildings;
    const Aabb box = s.meshes[o.mesh].box().transformed(o.transform);
    const Aabb area = city::block_area(p, i, j);
    EXPECT_TRUE(area.contains(box.min) && area.contains(box.max)) << o.name;
    // Inside its own lot, so buildings never overlap each other.
    const glm::dvec3 lot =
        area.min + glm::dvec3(k / p.buildings_per_block, 0, k % p.buildings_per_block) * city::kLot;
    EXPECT_GE(box.min.x, lot.x) << o.name;
    EXPECT_GE(box.min.z, lot.z) << o.name;
    EXPECT_LE(box.max.x, lot.x + city::kLot) << o.name;
    EXPECT_LE(box.max.z, lot.z + city::kLot) << o.name;
    EXPECT_EQ(box.min.y, 0.0) << o.name;
  }
  EXPECT_EQ(buildings, 3 * 2 * 3 * 3);
  // Block areas are separated by streets of kStreet.
  EXPECT_DOUBLE_EQ(city::block_area(p, 1, 0).min.x - city::block_area(p, 0, 0).max.x, city::kStreet);
  EXPECT_DOUBLE_EQ(city::block_area(p, 0, 1).min.z - city::block_area(p, 0, 0).max.z, city::kStreet);
  // The ground pieces tile the city, centred on the origin.
  const double half = 0.5 * 3 * city::block_pitch(p);
  EXPECT_EQ(s.bounds().min.x, -half);
  EXPECT_EQ(s.bounds().max.x, half);
}

TEST(City, FrontFacesAndNormalsPointOutward) {
  const Scene s = generate_city(small_city(2));
  for (const Mesh& m : s.meshes) {
    ASSERT_EQ(m.normals.size(), m.positions.size());
    const glm::vec3 centre(m.box().center());
    for (size_t t = 0; t < m.indices.size(); t += 3) {
      const uint32_t a = m.indices[t], b = m.indices[t + 1], c = m.indices[t + 2];
      const glm::vec3 face = glm::cross(m.positions[b] - m.positions[a], m.positions[c] - m.positions[a]);
      ASSERT_GT(glm::dot(face, m.normals[a]), 0.0f) << m.name;  // CCW front face = stored normal
      const glm::vec3 mid = (m.positions[a] + m.positions[b] + m.positions[c]) / 3.0f;
      if (m.name != "ground") {
        ASSERT_GT(glm::dot(mid - centre, m.normals[a]), 0.0f) << m.name;
      }
    }
  }
}

TEST(City, RejectsBadParams) {
  CityParams p;
  p.blocks_x = 0;
  EXPECT_THROW(generate_city(p), InputError);
  p = CityParams{};
  p.detail = 17;
  EXPECT_THROW(generate_city(p), InputError);
}

TEST(Layout, CopiesMultiplyAndShareMeshes) {
  const Scene asset = generate_city(small_city());
  const Scene s = layout_grid(asset, 2, 3, 0.25);
  EXPECT_EQ(s.meshes.size(), asset.meshes.size());
  ASSERT_EQ(s.objects.size(), 6 * asset.objects.size());
  EXPECT_EQ(s.triangle_count(), 6 * asset.triangle_count());
  const glm::dvec3 ext = asset.bounds().extent();
  const glm::dvec3 step(1.25 * ext.x, 0, 1.25 * ext.z);
  // Copy (1, 2) is the 6th: i outer, j inner.
  const Object& o = s.objects[5 * asset.objects.size() + 7];
  EXPECT_EQ(o.name, "copy 1,2/" + asset.objects[7].name);
  EXPECT_EQ(o.mesh, asset.objects[7].mesh);
  EXPECT_EQ(o.transform,
            glm::translate(glm::dmat4(1.0), glm::dvec3(step.x, 0, 2 * step.z)) * asset.objects[7].transform);
  EXPECT_NEAR(s.bounds().extent().x, ext.x + step.x, 1e-9);
  EXPECT_NEAR(s.bounds().extent().z, ext.z + 2 * step.z, 1e-9);
}

TEST(Specs, CityFields) {
  const Scene a = load_scene("city:3x4");
  EXPECT_EQ(a.source, "city:3x4");
  EXPECT_EQ(a.objects.size(), 3u * 4u * (1 + 16));
  const Scene b = load_scene("city:3x4:2:5:1");
  EXPECT_EQ(b.objects.size(), 3u * 4u * (1 + 4));
  EXPECT_LE(b.bounds().max.y, 5 * city::kFloorHeight);
  EXPECT_EQ(b.content_hash(), generate_city(occtest::city_params(3, 4, 2, 5, 1)).content_hash());
}

TEST(Specs, BadSpecsSayWhatIsWrong) {
  const std::pair<const char*, const char*> cases[] = {
      {"city:0x5", "--scene 'city:0x5': blocks must be 1..1000"},
      {"city:ax5", "--scene 'city:ax5': blocks must be 1..1000 (got 'a')"},
      {"city:5x-1", "blocks must be 1..1000 (got '-1')"},
      {"city:1001x1", "blocks must be 1..1000"},
      {"city:5", "blocks must be <X>x<Z>"},
      {"city:2x2:0", "buildings per block must be 1..64"},
      {"city:2x2:99999999999", "buildings per block must be 1..64"},
      {"city:2x2:4:201", "floors must be 1..200"},
      {"city:2x2:4:12:17", "detail must be 1..16"},
      {"city:2x2:4:12:2x", "detail must be 1..16 (got '2x')"},
      {"city:2x2:4:12:2:1", "expected city[:BXxBZ[:N[:F[:D]]]]"},
      {"city:", "blocks must be <X>x<Z>"},
      {"layout:0x2:a.glb", "copies must be 1..1000"},
      {"layout:2x2", "expected layout:NXxNZ:path"},
      {"cityscape", "unknown scene"},
      {"", "unknown scene"},
      {"scene.xyz", "unknown scene; expected path.gltf, path.glb, a model file (.ply, .obj"},
      {"scene.obj", "scene.obj: cannot open file"},
      {"missing.glb", "missing.glb: cannot open file"},
  };
  for (const auto& [spec, words] : cases)
    EXPECT_NE(spec_error(spec).find(words), std::string::npos) << spec << " -> " << spec_error(spec);
}

// Zero-area triangles (repeated indices, coincident or collinear vertices) cover nothing and are
// left out; every triangle with area stays, in order, however thin or small.
TEST(Mesh, ZeroAreaTrianglesAreLeftOutAndCounted) {
  Mesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {2, 0, 0}, {1e-7f, 1e-7f, 0}, {1e6f, 1, 0}, {1e6f, 1.0625f, 0},
                 {1e-3f, 0.5f, 0}, {1e6f, 17, 0}};
  m.indices = {0, 1, 2,   // a triangle
               0, 0, 1,   // repeated index
               0, 1, 3,   // collinear along x
               0, 4, 2,   // 1e-7 high over a unit edge: under 8 float ulps of its coordinates
               1, 3, 1,   // repeated index
               0, 5, 6,   // a sliver 1e6 long and 1/16 wide: one ulp at 1e6
               0, 7, 2,   // 1e-3 high over a unit edge: kept
               0, 5, 8};  // 1e6 long and 16 wide: 16 ulps at 1e6, kept
  EXPECT_EQ(drop_zero_area_triangles(m), 5u);
  EXPECT_EQ(m.indices, (std::vector<uint32_t>{0, 1, 2, 0, 7, 2, 0, 5, 8}));
  EXPECT_EQ(drop_zero_area_triangles(m), 0u);
}

// A triangle that repeats an earlier one of its mesh on the same positions (any vertices), in
// the same winding or (double-sided) either, and draws alike (uvs, colours, normals up to sign)
// is left out; everything else stays, in order.
TEST(Mesh, RepeatedTrianglesAreLeftOutAndCounted) {
  auto mesh = [] {
    Mesh m;
    // Vertices 0-2 a triangle; 3-5 the same positions again (normals opposite); 6 a fourth point.
    m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}};
    m.normals = {{0, 0, 1}, {0, 0, 1}, {0, 0, 1}, {0, 0, -1}, {0, 0, -1}, {0, 0, -1}, {0, 0, 1}};
    m.uvs = {{0, 0}, {1, 0}, {0, 1}, {0, 0}, {1, 0}, {0, 1}, {1, 1}};
    m.indices = {0, 1, 2,   // a triangle
                 1, 2, 0,   // itself rotated: a repeat in the same winding
                 3, 5, 4,   // reversed, on other vertices with opposite normals
                 4, 3, 5,   // reversed, rotated
                 1, 6, 2,   // a neighbour sharing an edge
                 5, 3, 4};  // same winding on the other vertices
    return m;
  };
  Mesh one = mesh();
  EXPECT_EQ(drop_repeated_triangles(one, false), 3u);  // 1 2 0, 4 3 5 (repeats 3 5 4), 5 3 4
  EXPECT_EQ(one.indices, (std::vector<uint32_t>{0, 1, 2, 3, 5, 4, 1, 6, 2}))
      << "single-sided: a reversed triangle is the other side's surface";
  Mesh both = mesh();
  EXPECT_EQ(drop_repeated_triangles(both, true), 4u);
  EXPECT_EQ(both.indices, (std::vector<uint32_t>{0, 1, 2, 1, 6, 2}));
  EXPECT_EQ(drop_repeated_triangles(both, true), 0u);

  // Corners that draw differently keep their triangle.
  Mesh uv = mesh();
  uv.uvs[4] = {0.5f, 0};
  EXPECT_EQ(drop_repeated_triangles(uv, true), 1u);  // only the rotated copy on vertices 0-2
  Mesh tilted = mesh();
  tilted.normals[3] = glm::normalize(glm::vec3(0, 1, -1));
  EXPECT_EQ(drop_repeated_triangles(tilted, true), 1u);  // only the rotated copy on vertices 0-2
  Mesh coloured = mesh();
  coloured.colors = {1, 1, 1, 2, 2, 2, 1};
  EXPECT_EQ(drop_repeated_triangles(coloured, true), 1u);
}
