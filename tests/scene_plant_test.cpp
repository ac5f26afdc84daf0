// The procedural plant (--scene plant:M, common/scene/plant.hpp): deterministic, about M million
// triangles, unique meshes, a walk down its aisle, clear errors for bad specs.
#include <gtest/gtest.h>

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <iostream>
#include <iterator>
#include <optional>
#include <random>
#include <set>

#include "common/camera_path.hpp"
#include "common/error.hpp"
#include "common/scene/hierarchy.hpp"
#include "common/scene/plant.hpp"
#include "common/scene/scene_cache.hpp"
#include "common/scene/scene_io.hpp"
#include "common/setup/scene_setup.hpp"
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

// ---- The scene cache (common/scene/scene_cache.hpp).

namespace {

std::string cache_dir(const std::string& name) {
  const std::string d = testing::TempDir() + "/occ_scene_cache_" + name + "_" + std::to_string(::getpid());
  std::filesystem::remove_all(d);
  return d;
}

std::vector<char> file_bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void write_bytes(const std::string& path, const std::vector<char>& bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), std::streamsize(bytes.size()));
}

// A plant scene, its hierarchy (default parameters) and its scene cache, saved as path =
// dir/p.scene (dir = cache_dir(name)) under key; error: what save_scene_cache said went wrong.
struct SavedPlant {
  Scene s;
  Hierarchy h;
  std::string dir, path;
  uint64_t key = 0;
  std::optional<std::string> error;
};

SavedPlant saved_plant(const std::string& spec, const std::string& name) {
  SavedPlant p{load_scene(spec), {}, cache_dir(name), "", scene_cache_key(spec, {}), std::nullopt};
  p.h = Hierarchy::build(p.s, {});
  p.path = p.dir + "/p.scene";
  p.error = save_scene_cache(p.path, p.key, p.s, p.h);
  return p;
}

}  // namespace

TEST(SceneCache, RoundTripRestoresTheSceneAndHierarchyExactly) {
  const auto [s, h, dir, path, key, error] = saved_plant("plant:0.05", "roundtrip");
  ASSERT_FALSE(error.has_value()) << *error;
  std::string why;
  auto back = load_scene_cache(path, key, &why);
  ASSERT_TRUE(back.has_value()) << why;
  EXPECT_EQ(back->scene.content_hash(), s.content_hash());
  EXPECT_EQ(back->hierarchy.fingerprint(), h.fingerprint());
  // The restored scene is the split one (clusters and the reordered indices), as the renderers
  // and the LOD builder need it: same clusters per mesh, same hash.
  ASSERT_EQ(back->hierarchy.size(), h.size());
  for (uint32_t id = 0; id < h.size(); ++id) {
    EXPECT_EQ(back->hierarchy.node(id).first_item, h.node(id).first_item);
    EXPECT_EQ(back->hierarchy.node(id).triangles, h.node(id).triangles);
    EXPECT_EQ(back->hierarchy.node(id).box.min, h.node(id).box.min);
  }
  ASSERT_EQ(back->scene.meshes.size(), s.meshes.size());
  for (size_t m = 0; m < s.meshes.size(); ++m) {
    ASSERT_EQ(back->scene.meshes[m].clusters.size(), s.meshes[m].clusters.size());
    EXPECT_EQ(back->scene.meshes[m].normals, s.meshes[m].normals);
    EXPECT_EQ(back->scene.meshes[m].name, s.meshes[m].name);
  }
  EXPECT_EQ(back->scene.objects.back().name, s.objects.back().name);
  EXPECT_EQ(back->scene.source, s.source);
  // Another spec or other hierarchy parameters: another key, the file is stale.
  EXPECT_NE(scene_cache_key("plant:0.06", {}), key);
  BuildParams other;
  other.arity = 4;
  EXPECT_FALSE(load_scene_cache(path, scene_cache_key("plant:0.05", other), &why).has_value());
  EXPECT_NE(why.find("stale"), std::string::npos) << why;
  EXPECT_TRUE(scene_cache_applies("plant:13"));
  EXPECT_FALSE(scene_cache_applies("city"));
  std::filesystem::remove_all(dir);
}

TEST(SceneCache, CorruptTruncatedOrWrongVersionFilesAreRejectedAndRebuiltByName) {
  const auto [s, h, dir, path, key, error] = saved_plant("plant:0.02", "corrupt");
  ASSERT_FALSE(error.has_value()) << *error;
  const std::vector<char> good = file_bytes(path);
  std::string why;
  for (size_t len : {size_t(0), size_t(7), size_t(20), size_t(35), size_t(36), good.size() / 2, good.size() - 1}) {
    write_bytes(path, std::vector<char>(good.begin(), good.begin() + ptrdiff_t(len)));
    EXPECT_FALSE(load_scene_cache(path, key, &why).has_value()) << len;
    EXPECT_TRUE(why.find("truncated") != std::string::npos) << len << ": " << why;
  }
  std::mt19937 rng(5);
  for (int k = 0; k < 60; ++k) {  // bit flips in the header and anywhere in the payload
    std::vector<char> bad = good;
    const size_t at = k < 36 ? size_t(k) : rng() % bad.size();
    bad[at] = char(bad[at] ^ (1 << (rng() % 8)));
    write_bytes(path, bad);
    EXPECT_FALSE(load_scene_cache(path, key, &why).has_value()) << at;
    EXPECT_FALSE(why.empty());
  }
  std::vector<char> bad = good;
  bad[8] = char(bad[8] + 1);  // format version
  write_bytes(path, bad);
  EXPECT_FALSE(load_scene_cache(path, key, &why).has_value());
  const unsigned version = uint8_t(good[8]);  // the format's version (u32, little-endian; < 255)
  EXPECT_NE(why.find("format version " + std::to_string(version + 1) + ", expected " + std::to_string(version)),
            std::string::npos)
      << why;
  bad = good;
  bad[0] = 'X';
  write_bytes(path, bad);
  EXPECT_FALSE(load_scene_cache(path, key, &why).has_value());
  EXPECT_NE(why.find("bad magic"), std::string::npos) << why;
  bad = good;
  bad[good.size() / 2] = char(bad[good.size() / 2] ^ 0x10);
  write_bytes(path, bad);
  EXPECT_FALSE(load_scene_cache(path, key, &why).has_value());
  EXPECT_NE(why.find("checksum"), std::string::npos) << why;
  EXPECT_FALSE(load_scene_cache(dir + "/none.scene", key, &why).has_value());
  EXPECT_EQ(why, "missing");

  // load_and_build: the first start writes the cache, the second reads it (same fingerprint),
  // a corrupt one is named, rebuilt and rewritten.
  SceneOptions o;
  o.spec = "plant:0.02";
  o.lod_cache = dir;
  const std::string cpath = scene_cache_path(dir, o.spec);
  testing::internal::CaptureStderr();
  const uint64_t fp1 = load_and_build(o, "t").fingerprint;
  std::string err = testing::internal::GetCapturedStderr();
  EXPECT_NE(err.find("wrote scene cache " + cpath), std::string::npos) << err;
  testing::internal::CaptureStderr();
  const LoadedScene second = load_and_build(o, "t");
  err = testing::internal::GetCapturedStderr();
  EXPECT_NE(err.find("read from scene cache " + cpath), std::string::npos) << err;
  EXPECT_EQ(second.fingerprint, fp1);
  EXPECT_EQ(second.fingerprint, h.fingerprint());
  EXPECT_EQ(second.scene.triangle_count(), s.triangle_count());
  std::vector<char> cached = file_bytes(cpath);
  cached[cached.size() - 3] ^= 0x40;
  write_bytes(cpath, cached);
  o.geometry_budget = "all";  // read whole: the payload's checksum (a lazy read checks ranges only)
  testing::internal::CaptureStderr();
  EXPECT_EQ(load_and_build(o, "t").fingerprint, fp1);
  err = testing::internal::GetCapturedStderr();
  EXPECT_NE(err.find("scene cache " + cpath + " is unusable (checksum mismatch (corrupt)): rebuilding it"),
            std::string::npos) << err;
  EXPECT_NE(err.find("wrote scene cache"), std::string::npos) << err;
  std::filesystem::remove_all(dir);
}
