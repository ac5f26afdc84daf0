// Model files other than glTF end to end: the shared glTF scenes written out as OBJ and PLY
// (model_files.hpp) render the glTF's frames in the reference renderer, and the glTF of their own
// (baked) geometry's to the pixel (sponza_lod4 is left out: it has no material, and glTF's default
// material is single-sided where a model file without materials is drawn double-sided); the three
// real processes at tau 0 render the reference's frames to the pixel on a model of each reader
// (PLY, OBJ, STL and FBX through Assimp), and the engine as FBX keeps the glTF's node tree and
// materials.
#include <gtest/gtest.h>

#include "cluster_run.hpp"
#include "common/scene/scene_io.hpp"
#include "model_files.hpp"
#include "render_client/tools/scene_export.hpp"

using namespace occtest;

namespace {

const std::vector<std::string> kView = {"--width", "192", "--height", "144"};

// frame_diff with `flags`; its summary line and the frames that differ in *summary.
int diff(const fs::path& a, const fs::path& b, const std::vector<std::string>& flags, std::string* summary) {
  const Outcome d = frame_diff(a, b, flags);
  *summary = diff_summary(d.log) + differing_frames(d.log);
  return d.code;
}

// A shared glTF scene and whether its PLY can draw it as the glTF does (PLY has no materials:
// opaque vertex colours, double-sided; the duplex has BLEND glass and single-sided walls).
struct SharedCase {
  const char* gltf;
  bool ply;
};

class SharedSceneAsModel : public ::testing::TestWithParam<SharedCase> {};

// The glTF, its OBJ and its PLY (vertex colours: its base colours) along the glTF's walk (saved:
// a walk follows the scene's bounds, and those of a rotated object's box are looser than its
// baked vertices'): the frames equal, bar the cluster tests' tolerance of a pixel in ten thousand,
// with PLY's colours within one level (the base colours as bytes). The pixels that differ are the
// baking's (the test below has the readers equal to the pixel): the engine's OBJ 1 pixel in 20
// frames, one shading level (its normal rotated in double and rounded, where the glTF's is rotated
// by the float normal matrix), its PLY 5 (coincident faces of two parts, which one mesh draws in
// another order; the OBJ, of the same floats, differs from the PLY by the same 5).
TEST_P(SharedSceneAsModel, ObjAndPlyRenderTheGltfFrames) {
  if (!have_shared()) GTEST_SKIP() << "../shared/scenes not found";
  const std::string gltf = std::string(OCC_SHARED_DIR) + "/scenes/" + GetParam().gltf;
  const fs::path dir = fresh_dir(fs::path(gltf).stem().string() + "_as_models");
  const occ::Scene s = occ::load_scene(gltf);
  const std::string obj = (dir / "scene.obj").string(), ply = (dir / "scene.ply").string();
  write_obj(s, obj);
  write_ply(s, ply, true, true);
  const std::vector<std::string> flags = {"--width", "192", "--height", "144", "--lod-cache", (dir / "cache").string()};
  const std::string walk = (dir / "gltf" / "path.csv").string();  // the cameras the glTF run showed
  const Outcome g = run_reference(dir / "gltf", gltf, "walk:20", flags);
  ASSERT_EQ(g.code, 0) << g.log;
  for (const auto& [name, scene] : {std::pair{"obj", obj}, {"ply", ply}}) {
    if (name == std::string("ply") && !GetParam().ply) continue;
    const Outcome r = run_reference(dir / name, scene, walk, flags);
    ASSERT_EQ(r.code, 0) << r.log;
  }
  std::string summary;
  EXPECT_EQ(diff(dir / "gltf", dir / "obj", {"--max-fraction", "0.0001"}, &summary), 0) << "OBJ: " << summary;
  EXPECT_NE(summary.find("frames=20"), std::string::npos) << summary;
  if (!GetParam().ply) return;
  EXPECT_EQ(diff(dir / "gltf", dir / "ply", {"--threshold", "1", "--max-fraction", "0.0001"}, &summary), 0)
      << "PLY: " << summary;
  EXPECT_NE(summary.find("frames=20"), std::string::npos) << summary;
}

// The same OBJ (without materials) and PLY (without colours) against the glTF of the geometry they
// hold (baked, model_files.hpp, written by scene_export's save_gltf: per-object colours, both
// sides drawn): every frame equal to the pixel. The OBJ against the glTF of the baked objects, the
// PLY (one mesh) against the glTF of one baked mesh. What the test above allows is the baking's
// rounding, not the readers'.
TEST_P(SharedSceneAsModel, ObjAndPlyRenderTheirGeometryAsGltfExactly) {
  if (!have_shared()) GTEST_SKIP() << "../shared/scenes not found";
  const std::string gltf = std::string(OCC_SHARED_DIR) + "/scenes/" + GetParam().gltf;
  const fs::path dir = fresh_dir(fs::path(gltf).stem().string() + "_baked");
  const occ::Scene s = occ::load_scene(gltf);
  const std::string obj = (dir / "scene.obj").string(), ply = (dir / "scene.ply").string();
  write_obj(s, obj, false);
  write_ply(s, ply, true, false);
  occ::save_gltf(baked(s, false), (dir / "objects.gltf").string());
  occ::save_gltf(baked(s, true), (dir / "one_mesh.gltf").string());
  const std::vector<std::string> flags = {"--width", "192", "--height", "144", "--lod-cache", (dir / "cache").string()};
  const std::string walk = (dir / "objects" / "path.csv").string();
  const Outcome g = run_reference(dir / "objects", (dir / "objects.gltf").string(), "walk:20", flags);
  ASSERT_EQ(g.code, 0) << g.log;
  for (const auto& [name, scene] :
       {std::pair{"obj", obj}, {"one_mesh", (dir / "one_mesh.gltf").string()}, {"ply", ply}}) {
    const Outcome r = run_reference(dir / name, scene, walk, flags);
    ASSERT_EQ(r.code, 0) << r.log;
  }
  std::string summary;
  EXPECT_EQ(diff(dir / "objects", dir / "obj", {"--max-fraction", "0"}, &summary), 0) << "OBJ: " << summary;
  EXPECT_NE(summary.find("frames=20 differing_pixels=0 "), std::string::npos) << "OBJ: " << summary;
  EXPECT_EQ(diff(dir / "one_mesh", dir / "ply", {"--max-fraction", "0"}, &summary), 0) << "PLY: " << summary;
  EXPECT_NE(summary.find("frames=20 differing_pixels=0 "), std::string::npos) << "PLY: " << summary;
}

INSTANTIATE_TEST_SUITE_P(Shared, SharedSceneAsModel,
                         ::testing::Values(SharedCase{"2CylinderEngine/2CylinderEngine.gltf", true},
                                           SharedCase{"duplex/Duplex_A_20110505.gltf", false}),
                         [](const auto& info) { return fs::path(info.param.gltf).stem().string().substr(0, 8); });

// The cluster's run of `o` against the reference's (expect_cluster_equals_reference), and every
// frame equal to the pixel.
void expect_cluster_equals_reference_exactly(const fs::path& dir, const ClusterOptions& o, size_t frames) {
  if (!expect_cluster_equals_reference(dir, o, kView, frames)) return;
  std::string summary;
  EXPECT_EQ(diff(dir / "reference", dir / "cluster", {"--max-fraction", "0"}, &summary), 0) << summary;
  EXPECT_NE(summary.find("frames=" + std::to_string(frames) + " differing_pixels=0 "), std::string::npos) << summary;
}

class ModelCluster : public ::testing::TestWithParam<const char*> {};

// plant:0.3 written as a model file (FBX: its OBJ written as FBX by Assimp): the cluster at tau 0
// renders the reference's frames, to the pixel.
TEST_P(ModelCluster, WalkEqualsReference) {
  const std::string ext = GetParam();
  const fs::path dir = fresh_dir("model_cluster_" + ext);
  const std::string file = (dir / ("plant." + ext)).string();
  const occ::Scene s = occ::load_scene("plant:0.3");
  if (ext == "ply") write_ply(s, file, true, true);
  else if (ext == "obj") write_obj(s, file);
  else if (ext == "stl") write_stl(s, file);
  else {
    const std::string obj = (dir / "plant.obj").string();
    write_obj(s, obj);
    ASSERT_TRUE(assimp_export_fbx(obj, file)) << "assimp export failed (Debian assimp-utils, scripts/setup.sh)";
  }
  ClusterOptions o(file, "walk:30", kView);
  o.all = {"--lod-cache", (dir / "cache").string()};
  expect_cluster_equals_reference_exactly(dir, o, 30);
}

INSTANTIATE_TEST_SUITE_P(Readers, ModelCluster, ::testing::Values("ply", "obj", "stl", "fbx"),
                         [](const auto& info) { return std::string(info.param); });

// The engine's glTF written as FBX by Assimp (model_files.hpp): --scene engine.fbx has the glTF's
// node tree (objects in the same order, each with its mesh and place; instancing kept),
// its materials' colours, and the cluster at tau 0 renders brute force's frames to the pixel.
TEST(FbxScene, EngineHierarchyMaterialsAndClusterEqualsReference) {
  if (!have_shared()) GTEST_SKIP() << "../shared/scenes not found";
  const std::string gltf = std::string(OCC_SHARED_DIR) + "/scenes/2CylinderEngine/2CylinderEngine.gltf";
  const fs::path dir = fresh_dir("engine_fbx");
  const std::string fbx = (dir / "engine.fbx").string();
  ASSERT_TRUE(assimp_export_fbx(gltf, fbx)) << "assimp export failed (Debian assimp-utils, scripts/setup.sh)";
  const occ::Scene g = occ::load_scene(gltf), f = occ::load_scene(fbx);
  ASSERT_EQ(f.objects.size(), g.objects.size());
  EXPECT_EQ(f.meshes.size(), g.meshes.size());
  EXPECT_EQ(f.triangle_count(), g.triangle_count());
  const double size = g.bounds().diagonal();
  for (size_t k = 0; k < g.objects.size(); ++k) {
    const occ::Object &a = g.objects[k], &b = f.objects[k];
    EXPECT_EQ(b.mesh, a.mesh) << k;
    EXPECT_EQ(f.meshes[b.mesh].triangle_count(), g.meshes[a.mesh].triangle_count()) << k;
    const occ::Aabb wa = g.meshes[a.mesh].box().transformed(a.transform);
    const occ::Aabb wb = f.meshes[b.mesh].box().transformed(b.transform);
    EXPECT_LT(glm::length(wa.min - wb.min) + glm::length(wa.max - wb.max), 1e-5 * size) << k << " " << a.name;
    const occ::Material *ma = g.material_of(a.mesh), *mb = f.material_of(b.mesh);
    ASSERT_TRUE(ma && mb) << k;
    EXPECT_EQ(mb->name, ma->name) << k;
    EXPECT_EQ(mb->base_color, ma->base_color) << k << " " << ma->name;
  }
  ClusterOptions o(fbx, "walk:20", kView);
  o.all = {"--lod-cache", (dir / "cache").string()};
  expect_cluster_equals_reference_exactly(dir, o, 20);
}

}  // namespace
