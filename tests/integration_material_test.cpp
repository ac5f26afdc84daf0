// Materials through the three real processes: cluster frames equal the reference renderer's
// frames exactly (frame_diff --max-fraction 0, not a tolerance) on a scene with BLEND glass, a
// MASK fence, single-sided walls seen from behind (culled: they must not occlude either) and a
// mirrored object, and on the shared duplex (single-sided materials and BLEND glass).
#include <gtest/gtest.h>

#include <cstdio>

#include "common/image.hpp"
#include "cluster_run.hpp"
#include "material_util.hpp"

using namespace occtest;
using namespace mattest;
using namespace std::chrono_literals;

namespace {

const std::vector<std::string> kView = {"--width", "192", "--height", "144"};

// frame_diff with no tolerance at all; its summary line in *summary.
int exact_diff(const fs::path& a, const fs::path& b, std::string* summary) {
  const Outcome diff = frame_diff(a, b, {"--max-fraction", "0"});
  *summary = diff_summary(diff.log);
  return diff.code;
}

size_t count(const std::string& s, const std::string& what) {
  size_t n = 0;
  for (size_t p = s.find(what); p != std::string::npos; p = s.find(what, p + 1)) ++n;
  return n;
}

occ::Image frame(const fs::path& dir, int f) {
  char name[32];
  std::snprintf(name, sizeof name, "frame_%05d.png", f);
  return occ::read_png((dir / name).string());
}

// Pixels within 2 levels of rgb.
size_t pixels_near(const occ::Image& img, int r, int g, int b) {
  size_t n = 0;
  for (size_t p = 0; p + 3 < img.rgba.size(); p += 4)
    n += std::abs(img.rgba[p] - r) <= 2 && std::abs(img.rgba[p + 1] - g) <= 2 && std::abs(img.rgba[p + 2] - b) <= 2;
  return n;
}

// The scene, seen from z ~ +9 looking down -z at (0, 0, -2):
//   blue BLEND glass (alpha 0.5, double-sided, unlit) 4 x 3 at z = 0; behind it a red unlit box at
//   z = -2 (the view's centre) and a green unlit box at (1.6, 0, -7) behind a single-sided wall at
//   z = -4 that faces away from the eye (culled: invisible and no occluder);
//   a lit opaque wall at x = -3.5, z = -3 hiding 8 yellow boxes at z = -6 (these are culled);
//   a MASK fence (checkerboard alpha texture, lit) at x = 3.2 in front of a magenta unlit box;
//   a mirrored lit box (scale -0.5, 0.5, 0.5) at (2.2, -1.2, -1), single-sided.
std::string write_scene(const fs::path& dir) {
  GltfBuilder b(dir);
  b.node(b.quad(b.material(mat({0, 0, 1, 0.5f}, "BLEND", true))), {0, 0, 0}, {4, 3, 1});
  b.node(b.box(b.material(mat({1, 0, 0, 1}))), {0, 0, -2});
  b.node(b.quad(b.material(mat({0.5f, 0.5f, 0.5f, 1}, "OPAQUE", false, false))), {1, 0, -4}, {5, 4, 1}, about_y(180));
  b.node(b.box(b.material(mat({0, 1, 0, 1}))), {1.6, 0, -7});
  b.node(b.quad(b.material(mat({0.8f, 0.7f, 0.6f, 1}, "OPAQUE", false, false))), {-3.5, 0, -3}, {3, 4, 1});
  const int yellow = b.box(b.material(mat({1, 1, 0, 1}, "OPAQUE", false, false)));
  for (int i = 0; i < 8; ++i) b.node(yellow, {-4.4 + 0.4 * (i % 4), -0.6 + 1.2 * (i / 4), -6}, glm::dvec3(0.3));
  occ::Image checker = solid(4, 4, {200, 200, 255, 255});
  for (int y = 0; y < 4; ++y)
    for (int x = 0; x < 4; ++x)
      if ((x + y) % 2) set_texel(checker, x, y, {0, 0, 0, 0});
  json fence = mat({1, 1, 1, 1}, "MASK", true, false);
  fence["pbrMetallicRoughness"]["baseColorTexture"] = {
      {"index", b.texture(checker, {{"magFilter", 9728}, {"minFilter", 9728}})}};
  b.node(b.quad(b.material(fence), true), {3.2, 1.0, -1}, {1.6, 1.6, 1});
  b.node(b.box(b.material(mat({1, 0, 1, 1}))), {3.2, 1.0, -2.5}, glm::dvec3(1.2));
  b.node(b.box(b.material(mat({0.3f, 0.6f, 0.9f, 1}, "OPAQUE", false, false))), {2.2, -1.2, -1}, {-0.5, 0.5, 0.5});
  return b.write_glb(dir / "materials.glb");
}

std::string write_path(const fs::path& file, int frames) {
  std::FILE* f = std::fopen(file.c_str(), "w");
  std::fprintf(f, "frame,eye_x,eye_y,eye_z,target_x,target_y,target_z,up_x,up_y,up_z,fovy_deg,near,far\n");
  for (int i = 0; i < frames; ++i) {
    const double t = double(i) / (frames - 1);
    std::fprintf(f, "%d,%.6f,%.6f,%.6f,0,0,-2,0,1,0,60,0.1,100\n", i, -1.0 + 2.0 * t, 0.4, 9.0 - 1.5 * t);
  }
  std::fclose(f);
  return file.string();
}

}  // namespace

// The switch culls with occlusion (--occlusion switch); then the switch sends frustum sets and
// the render client culls them itself in two passes (--occlusion client): glass
// never hides anything and the frames are the reference's either way.
TEST(ClusterMaterials, GlassFenceAndBackFacingWallsEqualTheReferenceExactly) {
  const fs::path dir = fresh_dir("materials");
  const std::string scene = write_scene(dir), path = write_path(dir / "path.csv", 24);
  const Outcome ref = run_reference(dir / "reference", scene, path, kView);
  ASSERT_EQ(ref.code, 0) << ref.log;
  for (const bool two_pass : {false, true}) {
    const std::string run = two_pass ? "two_pass" : "cluster";
    ClusterOptions o(scene, path, kView);
    o.occlusion = two_pass ? "client" : "switch";
    const ClusterRun r = run_cluster(dir / run, o);
    const std::string logs = r.logs();
    ASSERT_EQ(r.rvg_code, 0) << logs;
    EXPECT_EQ(r.node0_code, 0) << logs;
    EXPECT_EQ(r.node1_code, 0) << logs;
    std::string summary;
    EXPECT_EQ(exact_diff(dir / "reference", dir / run, &summary), 0) << run << ": " << summary;
    EXPECT_NE(summary.find("frames=24 differing_pixels=0 "), std::string::npos) << run << ": " << summary;

    // Each process says once which shader variants the scene uses.
    EXPECT_EQ(count(logs, "shader variants: shaded: "), 3u) << logs;
    EXPECT_NE(logs.find("BLEND 1"), std::string::npos) << logs;
    EXPECT_NE(logs.find("blended+unlit"), std::string::npos) << logs;
    EXPECT_NE(logs.find("textured+masked"), std::string::npos) << logs;

    for (int f : {2, 12, 23}) {
      const occ::Image img = frame(dir / run, f);
      // The red box behind the glass: red, then blue at 0.5 over it (glass never occludes).
      const uint8_t* c = &img.rgba[(size_t(72) * img.width + 96) * 4];
      EXPECT_NEAR(c[0], 128, 2) << run << " frame " << f;
      EXPECT_EQ(c[1], 0) << run << " frame " << f;
      EXPECT_NEAR(c[2], 128, 2) << run << " frame " << f;
      // The green box behind the back-facing single-sided wall, seen through the glass.
      EXPECT_GT(pixels_near(img, 0, 128, 128), 20u) << run << " frame " << f;
      // The magenta box through the fence's holes (alpha 0 texels).
      EXPECT_GT(pixels_near(img, 255, 0, 255), 20u) << run << " frame " << f;
    }
    // The opaque wall hides the 8 yellow boxes: from frame 2 on (occluders = the previous frame's
    // visible set) the switch culls them; in two passes, from frame 1 on (the first frame draws
    // everything in pass 1) the render client proves them hidden. 16 leaves in all (the
    // back-facing wall passes its query).
    auto stats = read_csv(dir / run / "stats.csv");
    ASSERT_EQ(stats["visible"].size(), 24u);
    for (size_t f = 1; f < 24; ++f) {
      if (two_pass) {
        EXPECT_EQ(stats["occlusion"][f], 0.0) << "frame " << f;
        EXPECT_GE(stats["two_pass"][f], 1.0) << "frame " << f;
        EXPECT_LE(stats["visible"][f] - stats["hidden_here"][f], 8.0) << "frame " << f;
      } else if (f >= 2) {
        EXPECT_LE(stats["visible"][f], 8.0) << "frame " << f;
      }
    }
  }
}

TEST(ClusterMaterials, DuplexWithSingleSidedMaterialsAndGlassEqualsTheReferenceExactly) {
  if (!have_shared()) GTEST_SKIP() << "../shared/scenes not found: the duplex test needs it";
  const fs::path dir = fresh_dir("duplex_exact");
  const std::string scene = shared("scenes/duplex/Duplex_A_20110505.gltf");
  ClusterOptions o(scene, "walk:60", kView);
  o.occlusion = "auto";  // the render client's default
  const ClusterRun r = run_cluster(dir / "cluster", o);
  const std::string logs = r.logs();
  ASSERT_EQ(r.rvg_code, 0) << logs;
  EXPECT_EQ(r.node0_code, 0) << logs;
  EXPECT_EQ(r.node1_code, 0) << logs;
  EXPECT_NE(logs.find("BLEND 3; textured 0, single-sided 19"), std::string::npos) << logs;
  ASSERT_EQ(run_reference(dir / "reference", scene, "walk:60", kView).code, 0);
  std::string summary;
  EXPECT_EQ(exact_diff(dir / "reference", dir / "cluster", &summary), 0) << summary;
  EXPECT_NE(summary.find("frames=60 differing_pixels=0 "), std::string::npos) << summary;
}
