// Model files other than glTF (model_reader.hpp): PLY through our reader (ASCII, binary of both
// byte orders, polygons, colours, other elements), OBJ, STL, OFF, COLLADA and FBX through Assimp
// (node tree, transforms, instancing, materials), --up z; bad and truncated files (one InputError naming
// the file and what is wrong, never half a scene); the scene cache of a model file.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <tuple>
#include <filesystem>
#include <fstream>

#include "common/error.hpp"
#include "common/image.hpp"
#include "common/scene/model_mesh.hpp"
#include "common/scene/model_reader.hpp"
#include "common/scene/ply_reader.hpp"
#include "common/scene/scene_io.hpp"
#include "common/setup/scene_setup.hpp"
#include "model_files.hpp"
#include "scene_fixtures.hpp"
#include "scratch_util.hpp"

using namespace occ;
namespace fs = std::filesystem;

namespace {

class ModelFiles : public occtest::ScratchDirTest {
 protected:
  std::string write(const std::string& name, const std::string& bytes) {
    const std::string p = (dir_ / name).string();
    std::ofstream(p, std::ios::binary) << bytes;
    return p;
  }
  std::string read(const std::string& path) {
    std::ifstream f(path, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(f), {});
  }
  // The InputError of load_model(path), "" if it loads.
  static std::string error_of(const std::string& path) {
    try {
      load_model(path);
    } catch (const InputError& e) {
      return e.what();
    }
    return "";
  }
};

// Two unit cubes, the second at x = 3, both of mesh 0 (a material of colour (0.25, 0.5, 0.75)).
Scene two_cubes() {
  Scene s = occtest::cube_grid(2, 3.0);
  s.objects.resize(2);
  Material m;
  m.base_color = {0.25f, 0.5f, 0.75f, 1.0f};
  s.materials.push_back(m);
  s.meshes[0].material = 0;
  return s;
}

std::vector<glm::vec3> world_positions(const Scene& s) {
  std::vector<glm::vec3> out;
  for (const Object& o : s.objects)
    for (uint32_t i : s.meshes[o.mesh].indices)
      out.push_back(glm::vec3(o.transform * glm::dvec4(glm::dvec3(s.meshes[o.mesh].positions[i]), 1.0)));
  return out;
}

TEST_F(ModelFiles, PlyAsciiAndBinaryReadTheTrianglesWritten) {
  const Scene s = two_cubes();
  occtest::write_ply(s, (dir_ / "a.ply").string(), false, true);
  occtest::write_ply(s, (dir_ / "b.ply").string(), true, true);
  for (const char* name : {"a.ply", "b.ply"}) {
    const Scene r = load_scene((dir_ / name).string());
    ASSERT_EQ(r.objects.size(), 1u) << name;
    EXPECT_EQ(r.triangle_count(), 24u) << name;
    EXPECT_EQ(world_positions(r), world_positions(s)) << name;  // same triangles, same order, exact floats
    ASSERT_EQ(r.meshes[0].colors.size(), r.meshes[0].positions.size());
    EXPECT_EQ(r.meshes[0].colors[0], 0xffbf8040u) << name;  // (64, 128, 191), opaque
    ASSERT_NE(r.material_of(0), nullptr);
    EXPECT_TRUE(r.material_of(0)->double_sided);
    EXPECT_FALSE(r.meshes[0].flat);  // the normals written
    EXPECT_EQ(r.files.size(), 1u);
  }
}

TEST_F(ModelFiles, PlyBigEndianQuadsDoublesAndOtherElementsWithoutColours) {
  std::string b =
      "ply\nformat binary_big_endian 1.0\ncomment a quad\nelement vertex 4\nproperty double x\nproperty double y\n"
      "property double z\nproperty uchar flags\nelement face 1\nproperty uchar kind\n"
      "property list uchar uint vertex_indices\nelement edge 1\nproperty list ushort int pair\nend_header\n";
  auto be = [&](const void* p, size_t n) {
    for (size_t i = n; i-- > 0;) b.push_back(static_cast<const char*>(p)[i]);
  };
  const double xyz[4][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  for (const auto& v : xyz) {
    for (double c : v) be(&c, 8);
    b.push_back(7);
  }
  b.push_back(1);
  b.push_back(4);
  for (uint32_t i : {0u, 1u, 2u, 3u}) be(&i, 4);
  const uint16_t two = 2;
  be(&two, 2);
  for (int32_t i : {0, 1}) be(&i, 4);
  const Scene s = load_model(write("quad.ply", b));
  ASSERT_EQ(s.meshes.size(), 1u);
  EXPECT_EQ(s.triangle_count(), 2u);  // the quad as a fan, winding kept
  const Mesh& m = s.meshes[0];
  EXPECT_EQ(m.positions[m.indices[0]], glm::vec3(0, 0, 0));
  EXPECT_EQ(m.positions[m.indices[1]], glm::vec3(1, 0, 0));
  EXPECT_EQ(m.positions[m.indices[2]], glm::vec3(1, 1, 0));
  EXPECT_TRUE(m.flat);  // no normals in the file
  EXPECT_EQ(m.material, kNoMaterial);
}

TEST_F(ModelFiles, BadPlyFilesNameTheFileAndThePlace) {
  const std::string head = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                           "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";
  const struct {
    std::string bytes, fragment;
  } cases[] = {
      {"plx\n", "not a PLY file"},
      {"ply\nformat ascii 2.0\nend_header\n", "header line 2"},
      {"ply\nformat ascii 1.0\nelement vertex 3\n", "no end_header"},
      {"ply\nformat ascii 1.0\nelement vertex 1\nproperty flot x\nend_header\n", "unknown property type"},
      {head + "0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n", "vertex index 3 out of range (3 vertices)"},
      {head + "0 0 0\n1 0 0\n0 1 0\n2 0 1\n", "a face of 2 vertices"},
      {head + "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n7\n", "bytes after the last element"},
      {head + "0 0 0\n1 0 0\n0 1 0\n", "element 'face' row 0 of 1"},
      {head + "0 0 0\n1 x 0\n0 1 0\n3 0 1 2\n", "'x' is not a number"},
      {head + "0 0 0\n1 1e39 0\n0 1 0\n3 0 1 2\n", "not a finite float"},
      {"ply\nformat ascii 1.0\nelement vertex 1\nproperty float y\nend_header\n0\n", "no x, y and z"},
      {"ply\nformat binary_little_endian 1.0\nelement vertex 4000000000\nproperty float x\nproperty float y\n"
       "property float z\nend_header\n", "cannot fit"},
  };
  int k = 0;
  for (const auto& c : cases) {
    const std::string path = write("bad" + std::to_string(k++) + ".ply", c.bytes);
    const std::string e = error_of(path);
    EXPECT_EQ(e.rfind(path + ": ", 0), 0u) << e;
    EXPECT_NE(e.find(c.fragment), std::string::npos) << "expected '" << c.fragment << "' in: " << e;
  }
  EXPECT_NE(error_of((dir_ / "missing.ply").string()).find("missing"), std::string::npos);
}

// A mesh above kMaxModelMeshTriangles comes as spatial parts within it: the same triangles and
// bounds, each part a mesh and an object of its own (the geometry budget streams meshes).
TEST_F(ModelFiles, BigMeshComesInSpatialPartsWithTheSameTriangles) {
  Scene s;
  Mesh grid;
  constexpr int kN = 730;  // 729 x 729 x 2 = 1,062,882 triangles
  for (int z = 0; z < kN; ++z)
    for (int x = 0; x < kN; ++x) grid.positions.push_back({float(x), float((x * 7 + z * 3) % 5), float(z)});
  for (int z = 0; z + 1 < kN; ++z)
    for (int x = 0; x + 1 < kN; ++x) {
      const uint32_t v = uint32_t(z * kN + x);
      grid.indices.insert(grid.indices.end(), {v, v + kN, v + 1, v + 1, v + kN, v + kN + 1});
    }
  compute_normals(grid);
  s.meshes.push_back(grid);
  s.objects.push_back(Object{0, glm::dmat4(1.0), "grid"});
  ASSERT_GT(s.triangle_count(), kMaxModelMeshTriangles);
  const std::string path = (dir_ / "grid.ply").string();
  occtest::write_ply(s, path, true, false);
  const Scene r = load_model(path);
  ASSERT_GE(r.meshes.size(), 2u);
  EXPECT_EQ(r.objects.size(), r.meshes.size());
  EXPECT_EQ(r.triangle_count(), s.triangle_count());
  for (const Mesh& m : r.meshes) EXPECT_LE(m.indices.size() / 3, kMaxModelMeshTriangles);
  EXPECT_EQ(r.bounds().min, s.bounds().min);
  EXPECT_EQ(r.bounds().max, s.bounds().max);
  std::vector<glm::vec3> a = world_positions(s), b = world_positions(r);
  auto less = [](const glm::vec3& p, const glm::vec3& q) { return std::tie(p.x, p.y, p.z) < std::tie(q.x, q.y, q.z); };
  std::sort(a.begin(), a.end(), less);
  std::sort(b.begin(), b.end(), less);
  EXPECT_TRUE(a == b);  // the same corners (the triangles, as sets of corners)
}

// A file cut anywhere is an error, never a scene with part of the file: binary and ASCII (whose
// last number must end with a newline, so that a number cut short is noticed).
TEST_F(ModelFiles, EveryTruncatedPlyIsAnError) {
  const Scene s = two_cubes();
  for (const bool binary : {true, false}) {
    const std::string whole_path = (dir_ / "whole.ply").string();
    occtest::write_ply(s, whole_path, binary, true);
    const std::string whole = read(whole_path);
    ASSERT_EQ(load_model(whole_path).triangle_count(), 24u);
    for (size_t n = 0; n + 1 < whole.size(); ++n) {
      const std::string path = write("cut.ply", whole.substr(0, n));
      EXPECT_NE(error_of(path), "") << (binary ? "binary" : "ascii") << " cut at " << n << " of " << whole.size();
    }
  }
}

TEST_F(ModelFiles, ObjObjectsMaterialsAndBlend) {
  Scene s = two_cubes();
  Material glass;
  glass.base_color = {0.1f, 0.2f, 0.3f, 0.5f};
  s.materials.push_back(glass);
  s.meshes.push_back(s.meshes[0]);
  s.meshes[1].material = 1;
  s.objects[1].mesh = 1;
  const std::string path = (dir_ / "cubes.obj").string();
  occtest::write_obj(s, path);
  const Scene r = load_scene(path);
  ASSERT_EQ(r.objects.size(), 2u);
  EXPECT_EQ(r.triangle_count(), 24u);
  EXPECT_EQ(world_positions(r).size(), 72u);
  const Material* a = r.material_of(r.objects[0].mesh);
  const Material* b = r.material_of(r.objects[1].mesh);
  ASSERT_TRUE(a && b);
  EXPECT_EQ(a->base_color, glm::vec4(0.25f, 0.5f, 0.75f, 1.0f));
  EXPECT_EQ(a->alpha_mode, AlphaMode::Opaque);
  EXPECT_FALSE(a->double_sided);
  EXPECT_EQ(b->alpha_mode, AlphaMode::Blend);
  EXPECT_FLOAT_EQ(b->base_color.a, 0.5f);
  EXPECT_EQ(r.bounds().min, s.bounds().min);
  EXPECT_EQ(r.bounds().max, s.bounds().max);
  ASSERT_EQ(r.files.size(), 2u);  // the OBJ and its MTL
  EXPECT_EQ(r.files[1].path.substr(r.files[1].path.size() - 9), "cubes.mtl");
}

// An OBJ material's map_Kd: decoded, sampled with the file's texture coordinates flipped to
// glTF's top-left origin, and listed among the scene's files (its cache goes stale with it).
TEST_F(ModelFiles, ObjTextureIsDecodedAndItsCoordinatesFlipped) {
  Image img;
  img.width = 2;
  img.height = 1;
  img.rgba = {255, 0, 0, 255, 0, 0, 255, 255};
  write_png((dir_ / "red_blue.png").string(), img);
  write("t.mtl", "newmtl painted\nKd 1 1 1\nmap_Kd red_blue.png\n");
  const std::string obj = write("t.obj", "mtllib t.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0.25\nvt 1 0.25\nvt 0 1\n"
                                         "usemtl painted\nf 1/1 2/2 3/3\n");
  const Scene s = load_model(obj);
  ASSERT_EQ(s.meshes.size(), 1u);
  const Material* m = s.material_of(0);
  ASSERT_NE(m, nullptr);
  ASSERT_EQ(m->base_color_texture, 0);
  ASSERT_EQ(s.images.size(), 1u);
  EXPECT_EQ(s.images[0].rgba, img.rgba);
  ASSERT_EQ(s.meshes[0].uvs.size(), s.meshes[0].positions.size());
  for (const glm::vec2& uv : s.meshes[0].uvs) EXPECT_TRUE(uv.y == 0.75f || uv.y == 0.0f) << uv.y;
  ASSERT_EQ(s.files.size(), 3u);  // the OBJ, its MTL, the PNG
  EXPECT_EQ(s.files[2].path, (dir_ / "red_blue.png").string());
  const std::string missing = write("u.obj", "mtllib u.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nusemtl x\nf 1/1 2/1 3/1\n");
  write("u.mtl", "newmtl x\nmap_Kd nowhere.png\n");
  const std::string e = error_of(missing);
  EXPECT_NE(e.find("cannot load texture"), std::string::npos) << e;
  EXPECT_EQ(e.rfind(missing + ": ", 0), 0u) << e;
}

TEST_F(ModelFiles, StlAndOffWithoutMaterialsGetTheObjectColour) {
  const std::string stl = (dir_ / "cubes.stl").string();
  occtest::write_stl(two_cubes(), stl);
  const Scene r = load_model(stl);
  EXPECT_EQ(r.triangle_count(), 24u);
  EXPECT_EQ(r.meshes[0].material, kNoMaterial);
  const std::string off = write("tri.off", "OFF\n4 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n3 0 2 3\n");
  EXPECT_EQ(load_model(off).triangle_count(), 2u);
  // A binary STL cut short is refused (Assimp checks its size against its triangle count).
  const std::string whole = read(stl);
  const std::string cut = write("cut.stl", whole.substr(0, whole.size() - 30));
  const std::string e = error_of(cut);
  EXPECT_EQ(e.rfind(cut + ": ", 0), 0u) << e;
}

// A COLLADA node tree: a parent translated by x = 10, a child under it rotated 90 degrees about z
// and instancing the same triangle as the parent (material "red", diffuse (0.8, 0.1, 0.1)).
const char* const kTreeDae = R"(<?xml version="1.0" encoding="utf-8"?>
<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">
  <asset><unit name="meter" meter="1"/><up_axis>Y_UP</up_axis></asset>
  <library_effects><effect id="red-fx"><profile_COMMON><technique sid="t"><lambert>
    <diffuse><color>0.8 0.1 0.1 1</color></diffuse></lambert></technique></profile_COMMON></effect></library_effects>
  <library_materials><material id="red" name="red"><instance_effect url="#red-fx"/></material></library_materials>
  <library_geometries><geometry id="tri" name="tri"><mesh>
    <source id="p"><float_array id="pa" count="9">0 0 0 1 0 0 0 1 0</float_array>
      <technique_common><accessor source="#pa" count="3" stride="3"><param name="X" type="float"/>
      <param name="Y" type="float"/><param name="Z" type="float"/></accessor></technique_common></source>
    <vertices id="v"><input semantic="POSITION" source="#p"/></vertices>
    <triangles count="1" material="m"><input semantic="VERTEX" source="#v" offset="0"/><p>0 1 2</p></triangles>
  </mesh></geometry></library_geometries>
  <library_visual_scenes><visual_scene id="s">
    <node id="parent" name="parent"><translate>10 0 0</translate><instance_geometry url="#tri"><bind_material>
      <technique_common><instance_material symbol="m" target="#red"/></technique_common></bind_material></instance_geometry>
      <node id="child" name="child"><rotate>0 0 1 90</rotate><instance_geometry url="#tri"><bind_material>
        <technique_common><instance_material symbol="m" target="#red"/></technique_common></bind_material></instance_geometry></node>
    </node>
  </visual_scene></library_visual_scenes>
  <scene><instance_visual_scene url="#s"/></scene>
</COLLADA>)";

// The tree above as read from `path`: two objects of one mesh, placed by the node tree, red.
void expect_tree(const Scene& r, const std::string& path) {
  ASSERT_EQ(r.objects.size(), 2u) << path;
  EXPECT_EQ(r.meshes.size(), 1u) << path;
  EXPECT_EQ(r.objects[0].mesh, r.objects[1].mesh) << path;
  EXPECT_EQ(r.objects[0].name, "parent") << path;
  EXPECT_EQ(r.objects[1].name, "child") << path;
  std::vector<glm::vec3> p = world_positions(r);
  ASSERT_EQ(p.size(), 6u) << path;
  auto near = [](glm::vec3 a, glm::vec3 b) { return glm::length(a - b) < 1e-5f; };
  EXPECT_TRUE(near(p[1], {11, 0, 0})) << path << ": " << p[1].x << " " << p[1].y;  // parent: (1,0,0) + 10
  EXPECT_TRUE(near(p[4], {10, 1, 0})) << path << ": " << p[4].x << " " << p[4].y;  // child: (1,0,0) turned to (0,1,0), + 10
  const Material* m = r.material_of(r.objects[0].mesh);
  ASSERT_NE(m, nullptr) << path;
  EXPECT_EQ(m->name, "red") << path;
  EXPECT_EQ(m->base_color, glm::vec4(0.8f, 0.1f, 0.1f, 1.0f)) << path;
}

TEST_F(ModelFiles, ColladaNodeTreeTransformsAndInstancing) {
  const std::string dae = write("tree.dae", kTreeDae);
  expect_tree(load_model(dae), dae);
}

// The same tree written as FBX by Assimp's exporter (model_files.hpp): the same objects, places
// and material; the file cut at the end of any line, or within one, is one error naming the file.
TEST_F(ModelFiles, FbxNodeTreeMaterialsAndEveryCutIsAnError) {
  const std::string dae = write("tree.dae", kTreeDae), fbx = (dir_ / "tree.fbx").string();
  ASSERT_TRUE(occtest::assimp_export_fbx(dae, fbx)) << "assimp export failed (Debian assimp-utils, scripts/setup.sh): "
                                                    << read(fbx + ".log");
  expect_tree(load_model(fbx), fbx);
  const std::string whole = read(fbx);
  std::vector<size_t> cuts = {whole.size() / 3, whole.size() / 2, whole.size() - 2};
  for (size_t at = whole.find('\n'); at + 1 < whole.size(); at = whole.find('\n', at + 1)) cuts.push_back(at + 1);
  for (const size_t n : cuts) {
    const std::string cut = write("cut.fbx", whole.substr(0, n));
    const std::string e = error_of(cut);
    EXPECT_EQ(e.rfind(cut + ": ", 0), 0u) << "cut at byte " << n << " of " << whole.size() << ": " << e;
  }
  EXPECT_GT(cuts.size(), 100u);
}

TEST_F(ModelFiles, BadObjFbxDaeStlFilesNameTheFile) {
  for (const auto& [name, bytes] : std::vector<std::pair<std::string, std::string>>{
           {"junk.obj", "this is not\x01\x02 an obj\n"},
           {"junk.fbx", "Kaydara FBX Binary  \x00\x1a\x00 junk"},
           {"junk.dae", "<COLLADA><library"},
           {"empty.stl", ""},
           {"points.obj", "v 0 0 0\nv 1 0 0\np 1\np 2\n"},
           {"cut.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 3\nf 2 4"},
           {"range.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n"}}) {
    const std::string path = write(name, bytes);
    const std::string e = error_of(path);
    EXPECT_EQ(e.rfind(path + ": ", 0), 0u) << name << ": " << e;
  }
  EXPECT_NE(occtest::spec_error("nothing/there.obj").find("nothing/there.obj"), std::string::npos);
}

TEST_F(ModelFiles, UpZTurnsTheSceneYUp) {
  const std::string ply = write("tall.ply",
                                "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                                "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
                                "0 0 0\n1 0 0\n0 2 5\n3 0 1 2\n");
  SceneOptions o;
  o.spec = ply;
  o.lod_cache = (dir_ / "cache_up").string();
  o.up = UpAxis::Z;
  ::testing::internal::CaptureStderr();
  const LoadedScene z = load_and_build(o, "test");
  ::testing::internal::GetCapturedStderr();
  EXPECT_FLOAT_EQ(float(z.scene.bounds().max.y), 5.0f);   // z became y
  EXPECT_FLOAT_EQ(float(z.scene.bounds().min.z), -2.0f);  // y became -z
}

// A model file's scene cache: written at the first start, read at the next (the same scene and
// hierarchy), keyed by --up, rebuilt when the file changes.
TEST_F(ModelFiles, SceneCacheIsReadUntilTheFileChanges) {
  SceneOptions o;
  o.spec = (dir_ / "plant.ply").string();
  o.lod_cache = (dir_ / "cache").string();
  occtest::write_ply(load_scene("plant:0.02"), o.spec, true, true);
  auto start = [&](std::string* log) {
    ::testing::internal::CaptureStderr();
    LoadedScene ls = load_and_build(o, "test");
    *log = ::testing::internal::GetCapturedStderr();
    return ls;
  };
  std::string log;
  const LoadedScene built = start(&log);
  EXPECT_NE(log.find("wrote scene cache"), std::string::npos) << log;
  const LoadedScene read_back = start(&log);
  EXPECT_NE(log.find("read from scene cache"), std::string::npos) << log;
  EXPECT_EQ(read_back.hierarchy.fingerprint(), built.hierarchy.fingerprint());
  EXPECT_EQ(read_back.scene.files, built.scene.files);
  EXPECT_GT(built.hierarchy.size(), 8u);  // one mesh, split into clusters: a tree to cull with
  occtest::write_ply(load_scene("plant:0.03"), o.spec, true, true);
  fs::last_write_time(o.spec, fs::last_write_time(o.spec) + std::chrono::seconds(1));
  const LoadedScene rebuilt = start(&log);
  EXPECT_NE(log.find("stale (" + o.spec + " changed"), std::string::npos) << log;
  EXPECT_GT(rebuilt.scene.triangle_count(), built.scene.triangle_count());
  o.up = UpAxis::Z;
  const LoadedScene turned = start(&log);
  EXPECT_NE(log.find("stale (written for another"), std::string::npos) << log;
  EXPECT_NE(turned.hierarchy.fingerprint(), rebuilt.hierarchy.fingerprint());
}

}  // namespace
