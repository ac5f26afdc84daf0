// load_gltf on small files written here: features (instancing, TRS, strides, strips/fans,
// skipped lines), malformed files (each must throw InputError naming the file and the element),
// and a fixed-seed fuzz (mutated/truncated files must load or throw InputError, never crash).
#include <gtest/gtest.h>
#include <unistd.h>

#include <cctype>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <glm/gtc/matrix_transform.hpp>
#include <iostream>
#include <nlohmann/json.hpp>
#include <random>

#include "common/error.hpp"
#include "common/scene/gltf_reader.hpp"
#include "common/scene/scene_cache.hpp"
#include "common/scene/scene_io.hpp"
#include "common/setup/scene_setup.hpp"
#include "scratch_util.hpp"

using namespace occ;
using nlohmann::json;
namespace fs = std::filesystem;

namespace {

// A glTF document under construction: JSON plus one binary buffer.
struct Gltf {
  json j = {{"asset", {{"version", "2.0"}}}, {"bufferViews", json::array()}, {"accessors", json::array()}};
  std::vector<unsigned char> bin;

  // Appends data (4-byte aligned) as a new buffer view; returns its index.
  template <class T>
  int view(const std::vector<T>& data, int stride = 0) {
    bin.resize((bin.size() + 3) / 4 * 4);
    json v = {{"buffer", 0}, {"byteOffset", bin.size()}, {"byteLength", data.size() * sizeof(T)}};
    if (stride) v["byteStride"] = stride;
    const auto* p = reinterpret_cast<const unsigned char*>(data.data());
    bin.insert(bin.end(), p, p + data.size() * sizeof(T));
    j["bufferViews"].push_back(v);
    return int(j["bufferViews"].size() - 1);
  }
  int accessor(int view, int component_type, size_t count, const char* type, size_t offset = 0) {
    j["accessors"].push_back({{"bufferView", view},
                              {"componentType", component_type},
                              {"count", count},
                              {"type", type},
                              {"byteOffset", offset}});
    return int(j["accessors"].size() - 1);
  }
  int positions(const std::vector<float>& xyz) { return accessor(view(xyz), 5126, xyz.size() / 3, "VEC3"); }
  int indices(const std::vector<uint16_t>& i) { return accessor(view(i), 5123, i.size(), "SCALAR"); }
};

constexpr int kFloat = 5126;

// Unit cube [0,1]^3 (12 triangles, no normals) drawn by node 0 "root" (translation 10,0,0) and
// its unnamed child node 1 (scale 2): one mesh, two instances.
Gltf cube() {
  Gltf g;
  const int pos = g.positions({0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0, 0, 0, 1, 1, 0, 1, 1, 1, 1, 0, 1, 1});
  const int idx = g.indices({0, 2, 1, 0, 3, 2, 4, 5, 6, 4, 6, 7, 0, 1, 5, 0, 5, 4,
                             3, 6, 2, 3, 7, 6, 0, 4, 7, 0, 7, 3, 1, 2, 6, 1, 6, 5});
  g.j["meshes"] = {{{"primitives", {{{"attributes", {{"POSITION", pos}}}, {"indices", idx}}}}}};
  g.j["nodes"] = {{{"name", "root"}, {"mesh", 0}, {"translation", {10, 0, 0}}, {"children", {1}}},
                  {{"mesh", 0}, {"scale", {2, 2, 2}}}};
  g.j["scenes"] = {{{"nodes", {0}}}};
  g.j["scene"] = 0;
  return g;
}

std::vector<unsigned char> bytes_of(const std::string& s) { return {s.begin(), s.end()}; }

void write_bytes(const fs::path& path, const std::vector<unsigned char>& data) {
  std::ofstream(path, std::ios::binary)
      .write(reinterpret_cast<const char*>(data.data()), std::streamsize(data.size()));
}

std::vector<unsigned char> read_bytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), {}};
}

// The .glb container of g: header, JSON chunk (space padded), BIN chunk (zero padded).
std::vector<unsigned char> glb_bytes(Gltf g) {
  g.j["buffers"] = {{{"byteLength", g.bin.size()}}};
  std::string text = g.j.dump();
  text.resize((text.size() + 3) / 4 * 4, ' ');
  g.bin.resize((g.bin.size() + 3) / 4 * 4, 0);
  std::vector<unsigned char> out;
  auto u32 = [&](uint32_t v) {
    for (int i = 0; i < 4; ++i) out.push_back((v >> (8 * i)) & 0xff);
  };
  out.insert(out.end(), {'g', 'l', 'T', 'F'});
  u32(2);
  u32(uint32_t(12 + 8 + text.size() + 8 + g.bin.size()));
  u32(uint32_t(text.size()));
  out.insert(out.end(), {'J', 'S', 'O', 'N'});
  out.insert(out.end(), text.begin(), text.end());
  u32(uint32_t(g.bin.size()));
  out.insert(out.end(), {'B', 'I', 'N', 0});
  out.insert(out.end(), g.bin.begin(), g.bin.end());
  return out;
}

// Writes and loads files in a scratch folder per test (dir_).
class GltfFiles : public occtest::ScratchDirTest {
 protected:
  // Writes g as name (.glb container, or .gltf + name.bin) and returns the path.
  std::string write(const std::string& name, Gltf g) const {
    const fs::path path = dir_ / name;
    if (path.extension() == ".glb") {
      write_bytes(path, glb_bytes(std::move(g)));
    } else {
      g.j["buffers"] = {{{"uri", name + ".bin"}, {"byteLength", g.bin.size()}}};
      write_bytes(dir_ / (name + ".bin"), g.bin);
      write_bytes(path, bytes_of(g.j.dump()));
    }
    return path.string();
  }

  // Expects load_gltf(path) to throw InputError whose message has the file name and every word.
  static void expect_error(const std::string& path, std::initializer_list<const char*> words) {
    try {
      load_gltf(path);
      ADD_FAILURE() << path << ": loaded, expected an error";
    } catch (const InputError& e) {
      const std::string msg = e.what();
      EXPECT_NE(msg.find(fs::path(path).filename().string()), std::string::npos) << msg;
      for (const char* w : words)
        EXPECT_NE(msg.find(w), std::string::npos) << "'" << w << "' not in: " << msg;
    }
  }
};

void expect_unit_normals(const Mesh& m) {
  ASSERT_EQ(m.normals.size(), m.positions.size());
  for (const glm::vec3& n : m.normals) ASSERT_NEAR(glm::length(n), 1.0f, 1e-4f);
}

}  // namespace

TEST_F(GltfFiles, CubeInstancedWithComposedTransforms) {
  for (const char* name : {"cube.gltf", "cube.glb"}) {
    SCOPED_TRACE(name);
    const Scene s = load_gltf(write(name, cube()));
    ASSERT_EQ(s.meshes.size(), 1u);
    ASSERT_EQ(s.objects.size(), 2u);
    EXPECT_EQ(s.triangle_count(), 24u);
    EXPECT_EQ(s.objects[0].name, "root");
    EXPECT_EQ(s.objects[1].name, "node 1");
    const glm::dmat4 root = glm::translate(glm::dmat4(1.0), glm::dvec3(10, 0, 0));
    EXPECT_EQ(s.objects[0].transform, root);
    EXPECT_EQ(s.objects[1].transform, glm::scale(root, glm::dvec3(2.0)));
    EXPECT_EQ(s.bounds(), (Aabb{{10, 0, 0}, {12, 2, 2}}));
    expect_unit_normals(s.meshes[0]);  // computed: the file has none
    EXPECT_TRUE(s.meshes[0].flat) << "glTF: a primitive without NORMAL is shaded flat";
  }
  EXPECT_EQ(load_gltf(write("a.gltf", cube())).content_hash(),
            load_gltf(write("a.glb", cube())).content_hash());
}

TEST_F(GltfFiles, RotationAndNoScenesLoadsAllRoots) {
  Gltf g = cube();
  g.j.erase("scenes");
  g.j.erase("scene");
  g.j["nodes"][0].erase("children");
  g.j["nodes"][1]["rotation"] = {0, std::sqrt(0.5), 0, std::sqrt(0.5)};  // 90 degrees about +y
  const Scene s = load_gltf(write("roots.gltf", g));
  ASSERT_EQ(s.objects.size(), 2u);
  const glm::dvec4 x = s.objects[1].transform * glm::dvec4(1, 0, 0, 1);
  EXPECT_NEAR(x.x, 0.0, 1e-12);
  EXPECT_NEAR(x.z, -2.0, 1e-12);  // scale 2, +x turns to -z
}

TEST_F(GltfFiles, InterleavedStrideNormalsAndByteIndices) {
  Gltf g;
  const std::vector<float> interleaved{0, 0, 0, 0, 0, 1, 1, 0, 0,
                                       0, 0, 1, 0, 1, 0, 0, 0, 1};  // position, normal
  const int view = g.view(interleaved, 24);
  const int pos = g.accessor(view, kFloat, 3, "VEC3", 0), nrm = g.accessor(view, kFloat, 3, "VEC3", 12);
  const int idx = g.accessor(g.view(std::vector<uint8_t>{0, 1, 2, 2, 2, 2}), 5121, 6, "SCALAR");
  g.j["meshes"] = {
      {{"primitives", {{{"attributes", {{"POSITION", pos}, {"NORMAL", nrm}}}, {"indices", idx}}}}}};
  g.j["nodes"] = {{{"mesh", 0}}};
  const Scene s = load_gltf(write("stride.glb", g));
  ASSERT_EQ(s.meshes.size(), 1u);
  const Mesh& m = s.meshes[0];
  EXPECT_EQ(m.positions, (std::vector<glm::vec3>{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}));
  EXPECT_EQ(m.normals, std::vector<glm::vec3>(3, {0, 0, 1}));
  EXPECT_FALSE(m.flat);  // the file's normals are used
  EXPECT_EQ(m.indices, (std::vector<uint32_t>{0, 1, 2}));  // the zero-area triangle left out, and counted
  EXPECT_EQ(s.zero_area_triangles, 1u);
}

// Exports make a surface two-sided by repeating every face reversed on the same vertices
// (bim/schependomlaan): with a double-sided material the repeats are left out (and counted per
// instance), so the cube loads as the plain one does, normals included (computed over both
// copies they would cancel); single-sided or BLEND, the repeats stay.
TEST_F(GltfFiles, FacesRepeatedReversedLoadOnce) {
  auto with_faces = [](bool repeat_reversed, json material) {
    Gltf g = cube();
    const std::vector<uint16_t> faces{0, 2, 1, 0, 3, 2, 4, 5, 6, 4, 6, 7, 0, 1, 5, 0, 5, 4,
                                      3, 6, 2, 3, 7, 6, 0, 4, 7, 0, 7, 3, 1, 2, 6, 1, 6, 5};
    std::vector<uint16_t> idx;
    for (size_t t = 0; t < faces.size(); t += 3) {
      idx.insert(idx.end(), {faces[t], faces[t + 1], faces[t + 2]});
      if (repeat_reversed) idx.insert(idx.end(), {faces[t], faces[t + 2], faces[t + 1]});
    }
    g.j["meshes"][0]["primitives"][0]["indices"] = g.indices(idx);
    g.j["meshes"][0]["primitives"][0]["material"] = 0;
    g.j["materials"] = {material};
    return g;
  };
  const json two_sided = {{"doubleSided", true}};
  const Scene plain = load_gltf(write("plain.gltf", with_faces(false, two_sided)));
  const Scene twice = load_gltf(write("twice.gltf", with_faces(true, two_sided)));
  ASSERT_EQ(twice.meshes.size(), 1u);
  EXPECT_EQ(twice.repeated_triangles, 24u);  // 12 per instance
  EXPECT_EQ(plain.repeated_triangles, 0u);
  EXPECT_EQ(twice.meshes[0].indices, plain.meshes[0].indices);
  EXPECT_EQ(twice.meshes[0].normals, plain.meshes[0].normals);
  expect_unit_normals(twice.meshes[0]);
  EXPECT_EQ(twice.content_hash(), plain.content_hash());

  const Scene one_sided = load_gltf(write("one_sided.gltf", with_faces(true, {{"doubleSided", false}})));
  EXPECT_EQ(one_sided.meshes[0].indices.size(), 72u);
  EXPECT_EQ(one_sided.repeated_triangles, 0u);
  const json glass = {{"doubleSided", true}, {"alphaMode", "BLEND"}};
  EXPECT_EQ(load_gltf(write("glass.gltf", with_faces(true, glass))).meshes[0].indices.size(), 72u);

  // The count comes back from the scene cache, and a start says it.
  SceneOptions o;
  o.spec = (dir_ / "twice.gltf").string();
  o.lod_cache = (dir_ / "cache").string();
  for (const char* from : {"wrote scene cache", "read from scene cache"}) {
    ::testing::internal::CaptureStderr();
    const LoadedScene ls = load_and_build(o, "test", false);
    const std::string log = ::testing::internal::GetCapturedStderr();
    EXPECT_NE(log.find(from), std::string::npos) << log;
    EXPECT_NE(log.find("24 repeated triangles of the file left out"), std::string::npos) << log;
    EXPECT_EQ(ls.scene.repeated_triangles, 24u);
    EXPECT_TRUE(ls.scene.meshes[0].flat);
  }
}

TEST_F(GltfFiles, StripsAndFansBecomeListsAndLinesAreSkipped) {
  Gltf g;
  // A 2x1 quad strip (4 triangles) and a 5-vertex fan (3 triangles), all facing +z.
  const int strip = g.positions({0, 1, 0, 0, 0, 0, 1, 1, 0, 1, 0, 0, 2, 1, 0, 2, 0, 0});
  const int fan = g.positions({0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0, -1, 0.5f, 0});
  g.j["meshes"] = {{{"primitives",
                     {{{"attributes", {{"POSITION", strip}}}, {"mode", 5}},
                      {{"attributes", {{"POSITION", fan}}}, {"mode", 6}},
                      {{"attributes", {{"POSITION", fan}}}, {"mode", 1}},
                      {{"attributes", {{"POSITION", fan}}}, {"mode", 0}}}}}};
  g.j["nodes"] = {{{"mesh", 0}}, {{"mesh", 0}}};  // skipped primitives are counted once per mesh
  ::testing::internal::CaptureStderr();
  const Scene s = load_gltf(write("modes.gltf", g));
  const std::string err = ::testing::internal::GetCapturedStderr();
  EXPECT_NE(err.find("modes.gltf: skipped 2 non-triangle primitives (lines/points)"), std::string::npos)
      << err;
  ASSERT_EQ(s.meshes.size(), 2u);
  EXPECT_EQ(s.objects.size(), 4u);
  EXPECT_EQ(s.meshes[0].triangle_count(), 4u);
  EXPECT_EQ(s.meshes[1].triangle_count(), 3u);
  for (const Mesh& m : s.meshes)
    for (size_t t = 0; t < m.indices.size(); t += 3) {
      const glm::vec3 a = m.positions[m.indices[t]], b = m.positions[m.indices[t + 1]],
                      c = m.positions[m.indices[t + 2]];
      EXPECT_GT(glm::cross(b - a, c - a).z, 0.0f) << m.name << " triangle " << t / 3;
    }
}

TEST_F(GltfFiles, MalformedFilesNameFileAndPlace) {
  expect_error((dir_ / "missing.gltf").string(), {"cannot open"});

  write_bytes(dir_ / "bad_json.gltf", bytes_of("{ \"asset\": { \"version\": \"2.0\" }, "));
  expect_error((dir_ / "bad_json.gltf").string(), {"invalid glTF"});

  Gltf g = cube();
  g.j["nodes"][1]["mesh"] = 9;
  expect_error(write("mesh_range.glb", g), {"node 1: mesh 9 out of range (1 meshes)"});

  g = cube();
  g.j["accessors"][0]["count"] = 9;
  expect_error(write("accessor_bounds.gltf", g),
               {"mesh 0 primitive 0: accessor 0 reads past the end of buffer view 0"});

  g = cube();
  g.j["bufferViews"][1]["byteLength"] = 1000;
  expect_error(write("view_bounds.gltf", g), {"buffer view 1 reads past the end of buffer 0"});

  g = cube();
  g.j["meshes"][0]["primitives"][0]["attributes"]["POSITION"] = 7;
  expect_error(write("accessor_range.gltf", g),
               {"mesh 0 primitive 0: accessor 7 out of range (2 accessors)"});

  g = cube();
  g.j["accessors"][0]["type"] = "VEC2";
  expect_error(write("position_type.gltf", g), {"POSITION accessor 0 must be float VEC3"});

  g = cube();
  g.bin[96 + 2 * 5] = 8;  // sixth index (u16 at offset 96) -> 8
  expect_error(write("index_range.glb", g), {"mesh 0 primitive 0: index 8 >= vertex count 8"});

  g = cube();
  g.j["accessors"][1]["count"] = 35;
  expect_error(write("index_count.gltf", g), {"index count 35 is not a multiple of 3"});

  g = cube();
  const float nan = std::nanf("");
  std::memcpy(&g.bin[4], &nan, 4);
  expect_error(write("nan.glb", g), {"POSITION accessor 0: element 0 is not finite"});

  g = cube();
  g.j["nodes"][1]["children"] = {0};
  expect_error(write("cycle.gltf", g), {"node 0: the node hierarchy has a cycle"});

  g = cube();
  g.j["nodes"].push_back({{"children", {1}}});
  expect_error(write("two_parents.gltf", g), {"node 1: has two parents (nodes 0 and 2)"});

  g = cube();
  g.j["nodes"][0]["children"] = {5};
  expect_error(write("child_range.gltf", g), {"node 0: child node 5 out of range (2 nodes)"});

  g = cube();
  g.j["scenes"][0]["nodes"] = {0, 1};
  expect_error(write("root_child.gltf", g), {"scene 0: root node 1 is a child of node 0"});

  g = cube();
  g.j["scene"] = 3;
  expect_error(write("scene_range.gltf", g), {"default scene: scene 3 out of range (1 scenes)"});

  g = cube();
  g.j["nodes"][0]["scale"] = {1e300, 1e300, 1e300};
  g.j["nodes"][1]["scale"] = {1e300, 1e300, 1e300};
  expect_error(write("huge.gltf", g), {"node 1: world transform is not finite"});

  g = cube();
  g.j["nodes"][0]["translation"] = {1, 2};
  expect_error(write("trs.gltf", g), {"node 0: translation must have 3 numbers"});

  g = cube();
  g.j["meshes"][0]["primitives"][0]["mode"] = 9;
  expect_error(write("mode.gltf", g), {"mode 9 is not a glTF primitive mode"});

  g = cube();
  g.j["accessors"][0]["sparse"] = {{"count", 1},
                                   {"indices", {{"bufferView", 1}, {"componentType", 5123}}},
                                   {"values", {{"bufferView", 0}}}};
  expect_error(write("sparse.gltf", g), {"accessor 0: sparse accessors are not supported"});

  g = cube();
  g.j["buffers"] = {{{"uri", "nowhere.bin"}, {"byteLength", 4}}};
  write_bytes(dir_ / "no_bin.gltf", bytes_of(g.j.dump()));
  expect_error((dir_ / "no_bin.gltf").string(), {"nowhere.bin"});

  std::vector<unsigned char> glb = glb_bytes(cube());
  write_bytes(dir_ / "truncated.glb", {glb.begin(), glb.begin() + std::ptrdiff_t(glb.size() / 2)});
  expect_error((dir_ / "truncated.glb").string(), {"invalid glTF"});
  glb[3] = 'X';
  write_bytes(dir_ / "magic.glb", glb);
  expect_error((dir_ / "magic.glb").string(), {"invalid glTF", "magic"});
}

// Byte mutations and truncations of a valid cube: every load succeeds or throws InputError.
TEST_F(GltfFiles, FuzzedFilesLoadOrThrowInputError) {
  Gltf g = cube();
  g.j["meshes"][0]["primitives"].push_back({{"attributes", {{"POSITION", 0}}}, {"mode", 5}});
  const std::vector<unsigned char> glb = glb_bytes(g);
  const std::vector<unsigned char> text = read_bytes(write("fuzz.gltf", g));  // fuzz.gltf.bin stays intact

  // Digit positions in the JSON (the .glb JSON chunk starts at byte 20): changing a digit keeps
  // the JSON valid and reaches the loader's own index/bounds checks.
  auto digits = [](const std::vector<unsigned char>& d, size_t begin, size_t end) {
    std::vector<size_t> pos;
    for (size_t i = begin; i < end; ++i)
      if (std::isdigit(d[i])) pos.push_back(i);
    return pos;
  };
  uint32_t json_size;
  std::memcpy(&json_size, &glb[12], 4);
  const std::vector<size_t> glb_digits = digits(glb, 20, 20 + json_size),
                            text_digits = digits(text, 0, text.size());

  std::mt19937 rng(12345);  // engine output is specified by the standard: same run everywhere
  int loaded = 0, rejected = 0;
  ::testing::internal::CaptureStderr();  // tinygltf warnings and skip notes of 2000 loads
  for (int iter = 0; iter < 2000; ++iter) {
    const bool binary = iter % 2 == 0;
    std::vector<unsigned char> data = binary ? glb : text;
    const std::vector<size_t>& digit_pos = binary ? glb_digits : text_digits;
    const uint32_t kind = rng() % 8;  // 0: truncate, 1-4: change digits, 5-7: change any bytes
    if (kind == 0) data.resize(rng() % data.size());
    for (uint32_t k = 0, n = kind == 0 ? 0 : 1 + rng() % 4; k < n; ++k) {
      if (kind <= 4)
        data[digit_pos[rng() % digit_pos.size()]] = static_cast<unsigned char>('0' + rng() % 10);
      else
        data[rng() % data.size()] = static_cast<unsigned char>(rng());
    }
    const fs::path path = dir_ / (binary ? "fuzz.glb" : "fuzz.gltf");
    write_bytes(path, data);
    try {
      load_gltf(path.string());
      ++loaded;
    } catch (const InputError&) {
      ++rejected;
    } catch (const std::exception& e) {
      ADD_FAILURE() << "iteration " << iter << ": not an InputError: " << e.what();
    }
  }
  ::testing::internal::GetCapturedStderr();
  std::cout << "fuzz: " << loaded << " loaded, " << rejected << " rejected\n";
  EXPECT_GT(loaded, 0);
  EXPECT_GT(rejected, 0);
}

TEST_F(GltfFiles, LayoutSpecOfAFile) {
  const std::string path = write("asset.glb", cube());
  const Scene asset = load_gltf(path);
  const Scene s = load_scene("layout:3x2:" + path);
  EXPECT_EQ(s.source, "layout:3x2:" + path);
  EXPECT_EQ(s.objects.size(), 6 * asset.objects.size());
  EXPECT_EQ(s.meshes.size(), asset.meshes.size());
  EXPECT_EQ(s.triangle_count(), 6 * asset.triangle_count());
  // Footprint 2 x 2, gap 0.25: copies every 2.5 m.
  EXPECT_EQ(s.bounds(), (Aabb{{10, 0, 0}, {10 + 2 * 2.5 + 2, 2, 2.5 + 2}}));
  EXPECT_THROW(load_scene("layout:3x2:" + (dir_ / "none.glb").string()), InputError);
}

// Only the effects a scene calls for: in a scene of two cubes LODs could save a few triangles at
// most, so --pixel-error > 0 loads no LODs there (every process draws full detail, as with
// --pixel-error 0), while a city keeps them.
TEST_F(GltfFiles, LowPolySceneSkipsLodSelection) {
  SceneOptions cubes;
  cubes.spec = write("cubes.gltf", cube());
  cubes.lod_cache = (dir_ / "cache").string();
  const LoadedScene a = load_and_build(cubes, "test", /*with_lod=*/true);
  EXPECT_EQ(a.lod, nullptr);

  SceneOptions city;
  city.spec = "city:6x6:3:10:1";  // the scene of the cluster LOD tests
  city.lod_cache = (dir_ / "cache").string();
  const LoadedScene b = load_and_build(city, "test", true);
  ASSERT_NE(b.lod, nullptr);
  EXPECT_TRUE(lod_benefit(*b.lod, b.hierarchy).worth_selecting());
}

// A glTF scene's cache: written at the first start, read at the next while its files
// are unchanged, rebuilt when one of them changed; read lazily where its arrays exceed the
// geometry budget, and then each mesh read back is the mesh of the file.
TEST_F(GltfFiles, SceneCacheIsReadUntilAFileChangesAndLazilyAboveTheBudget) {
  Gltf g;  // a 200 x 200 vertex grid: 39,601 x 2 triangles, 1.9 MB of arrays once loaded
  std::vector<float> xyz;
  std::vector<uint16_t> idx;
  constexpr int kN = 200;
  for (int z = 0; z < kN; ++z)
    for (int x = 0; x < kN; ++x) xyz.insert(xyz.end(), {float(x), 0.01f * float((x * 7 + z * 3) % 5), float(z)});
  for (int z = 0; z + 1 < kN; ++z)
    for (int x = 0; x + 1 < kN; ++x) {
      const auto v = uint16_t(z * kN + x);
      idx.insert(idx.end(), {v, uint16_t(v + kN), uint16_t(v + 1), uint16_t(v + 1), uint16_t(v + kN), uint16_t(v + kN + 1)});
    }
  const int pos = g.positions(xyz), ind = g.indices(idx);
  g.j["meshes"] = {{{"primitives", {{{"attributes", {{"POSITION", pos}}}, {"indices", ind}}}}}};
  g.j["nodes"] = {{{"name", "grid"}, {"mesh", 0}}};
  SceneOptions o;
  o.spec = write("grid.gltf", g);
  o.lod_cache = (dir_ / "cache").string();
  const Scene file = load_gltf(o.spec);
  ASSERT_EQ(file.files.size(), 2u);  // the .gltf and its .bin
  EXPECT_EQ(file.files[1].path, (dir_ / "grid.gltf.bin").string());
  ASSERT_GT(scene_array_bytes(file), uint64_t(1) << 20);
  auto start = [&](const std::string& budget, std::string* log) {
    o.geometry_budget = budget;
    ::testing::internal::CaptureStderr();
    LoadedScene ls = load_and_build(o, "test", false);
    *log = ::testing::internal::GetCapturedStderr();
    return ls;
  };
  std::string log;
  const LoadedScene built = start("all", &log);
  EXPECT_NE(log.find("wrote scene cache"), std::string::npos) << log;
  const LoadedScene read = start("all", &log);
  EXPECT_NE(log.find("read from scene cache"), std::string::npos) << log;
  EXPECT_EQ(read.scene.content_hash(), built.scene.content_hash());
  EXPECT_EQ(read.scene.files, file.files);
  EXPECT_EQ(read.hierarchy.fingerprint(), built.hierarchy.fingerprint());
  EXPECT_EQ(read.scene.mapped, nullptr);

  // Under a budget of 1 MB the arrays stay in the file; every mesh read back is the file's.
  const LoadedScene lazy = start("1", &log);
  EXPECT_NE(log.find("read from scene cache"), std::string::npos) << log;
  ASSERT_NE(lazy.scene.mapped, nullptr);
  EXPECT_EQ(lazy.hierarchy.fingerprint(), built.hierarchy.fingerprint());
  ASSERT_EQ(lazy.scene.meshes.size(), built.scene.meshes.size());
  for (uint32_t m = 0; m < built.scene.meshes.size(); ++m) {
    const Mesh back = read_mapped_mesh(lazy.scene, m);
    EXPECT_EQ(back.positions, built.scene.meshes[m].positions) << m;
    EXPECT_EQ(back.indices, built.scene.meshes[m].indices) << m;
  }
  // A budget the arrays fit in: read whole.
  EXPECT_EQ(start("64", &log).scene.mapped, nullptr);

  // The .bin changes (one vertex moves up, the file a second newer): stale, named, rebuilt.
  std::vector<unsigned char> bin = read_bytes(dir_ / "grid.gltf.bin");
  const float up = 5.0f;
  std::memcpy(bin.data() + 4, &up, 4);  // vertex 0's y (positions first in the buffer)
  write_bytes(dir_ / "grid.gltf.bin", bin);
  fs::last_write_time(dir_ / "grid.gltf.bin", fs::last_write_time(dir_ / "grid.gltf.bin") + std::chrono::seconds(1));
  const LoadedScene rebuilt = start("all", &log);
  EXPECT_NE(log.find("stale (" + (dir_ / "grid.gltf.bin").string() + " changed"), std::string::npos) << log;
  EXPECT_NE(log.find("wrote scene cache"), std::string::npos) << log;
  EXPECT_NE(rebuilt.scene.content_hash(), built.scene.content_hash());
  EXPECT_EQ(rebuilt.scene.content_hash(), start("all", &log).scene.content_hash());  // the cache just written
  EXPECT_GE(rebuilt.scene.bounds().max.y, 5.0f);
}
