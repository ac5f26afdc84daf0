// Every culling method draws brute force's frames exactly, pixel for pixel: CHC and
// stop-and-wait (one process), the switch (three processes), the switch's frustum sets culled by the
// render client in two passes, and the depth-readback occlusion server (GigaWalk), against
// `--cull none`, on
//   - hard:cracks: walls and slabs as separate meshes that abut (T-junctions, vertices that do not
//     match) or leave seams of 0.5 to 24 mm (0.03 to 3 pixels), cubes of 2 to 10 mm right behind
//     the seams and a field of 3 mm cubes: the pixels real building exports got wrong; walks at
//     256^2, 512^2 and 1024^2, an orbit, and far from the origin;
//   - every shared real scene (../shared/scenes, skipped where absent), a walk at 256^2 and an
//     orbit at 512^2: the three building exports of bim/ (duplicate faces, cracks, glass, zero-area
//     triangles: two of these views had one wrong pixel while the loader kept those), the duplex,
//     the saw, the engine and the one-mesh Sponza.
// CTest label "matrix": scripts/test.sh runs it; the sanitizer suite leaves it out (the same code
// paths run there in the cluster, hard and baseline tests).
#include <gtest/gtest.h>

#include <cstring>

#include "common/cull/enclosure.hpp"
#include "common/image.hpp"
#include "common/scene/scene_io.hpp"
#include "integration_util.hpp"

using namespace occtest;
using namespace std::chrono_literals;

namespace {

struct View {
  std::string scene;  // a --scene spec, or a file under ../shared/scenes when `shared`
  const char* path;
  int size;  // viewport size x size
  bool shared = false;
};
void PrintTo(const View& v, std::ostream* os) { *os << v.scene << " " << v.path << " " << v.size; }

void expect_identical(const fs::path& reference, const fs::path& frames, const std::string& what) {
  const Outcome d = frame_diff(reference, frames, {"--max-fraction", "0"});
  EXPECT_EQ(d.code, 0) << what << ": " << diff_summary(d.log);
  EXPECT_NE(diff_summary(d.log).find("differing_pixels=0 "), std::string::npos) << what << ": " << d.log;
}

class EveryMethod : public ::testing::TestWithParam<View> {};

TEST_P(EveryMethod, DrawsBruteForcesFrames) {
  View v = GetParam();
  if (v.shared) {
    if (!have_shared()) GTEST_SKIP() << "../shared/scenes not found: this view needs " << v.scene;
    v.scene = shared("scenes/" + v.scene);
  }
  const fs::path dir = fresh_dir("every_method");
  const std::string size = std::to_string(v.size);
  const std::vector<std::string> view = {"--width", size, "--height", size};
  auto with = [&](std::vector<std::string> f) {
    f.insert(f.end(), view.begin(), view.end());
    return f;
  };
  const Outcome none = run_reference(dir / "none", v.scene, v.path, with({"--cull", "none"}));
  ASSERT_EQ(none.code, 0) << none.log;
  for (const std::string cull : {"chc", "stop-and-wait"}) {
    const Outcome o = run_reference(dir / cull, v.scene, v.path, with({"--cull", cull}));
    ASSERT_EQ(o.code, 0) << cull << ": " << o.log;
    expect_identical(dir / "none", dir / cull, cull);
  }
  ::setenv("OCC_BIN", OCC_BIN_DIR, 1);
  const std::string cluster_sh = std::string(OCC_SOURCE_DIR) + "/scripts/cluster.sh";
  for (const auto& [name, flags] : std::vector<std::pair<std::string, std::vector<std::string>>>{
           {"switch", {}}, {"two_pass", {"--occlusion", "client"}}}) {
    std::vector<std::string> a = {"/bin/bash", cluster_sh, "--scene", v.scene, "--path", v.path, "--out",
                                  (dir / name).string()};
    a.insert(a.end(), flags.begin(), flags.end());
    const Outcome o = run_to_end(with(a), dir / (name + ".log"), 300s);
    ASSERT_EQ(o.code, 0) << name << ": " << o.log;
    expect_identical(dir / "none", dir / name, name);
  }
  const fs::path gw = dir / "gigawalk";
  fs::create_directories(gw);
  Proc server(with({bin("occlusion_server"), "--scene", v.scene, "--port-file", (gw / "port").string(),
                    "--timeout-ms", "30000"}),
              gw / "server.log");
  const int port = wait_port(gw / "port", server);
  ASSERT_NE(port, 0) << server.log();
  const Outcome client = run_to_end(with({bin("render_client"), "--scene", v.scene, "--path", v.path, "--connect",
                                          "127.0.0.1:" + std::to_string(port), "--out", gw.string()}),
                                    gw / "client.log", 300s);
  ASSERT_EQ(client.code, 0) << client.log;
  EXPECT_EQ(server.wait(30s), 0) << server.log();
  expect_identical(dir / "none", gw, "gigawalk");
}

INSTANTIATE_TEST_SUITE_P(Cracks, EveryMethod,
                         ::testing::Values(View{"hard:cracks", "walk:40", 256}, View{"hard:cracks", "walk:40", 512},
                                           View{"hard:cracks", "walk:24", 1024}, View{"hard:cracks", "orbit:24", 512},
                                           View{"offset:1e5,0,-3e4:hard:cracks", "walk:40", 512}));

INSTANTIATE_TEST_SUITE_P(Structures, EveryMethod,
                         ::testing::Values(View{"office:4", "walk:40", 256}, View{"pipes:4", "orbit:16", 512}));

INSTANTIATE_TEST_SUITE_P(
    Shared, EveryMethod,
    ::testing::Values(View{"bim/schependomlaan/schependomlaan.gltf", "walk:30", 256, true},
                      View{"bim/schependomlaan/schependomlaan.gltf", "orbit:30", 512, true},
                      View{"bim/sgd_bodo/sgd_bodo.gltf", "walk:30", 256, true},
                      View{"bim/sgd_bodo/sgd_bodo.gltf", "orbit:20", 512, true},
                      View{"bim/denhaag_city/denhaag_city.gltf", "walk:30", 256, true},
                      View{"bim/denhaag_city/denhaag_city.gltf", "orbit:20", 512, true},
                      View{"duplex/Duplex_A_20110505.gltf", "walk:30", 256, true},
                      View{"duplex/Duplex_A_20110505.gltf", "orbit:16", 512, true},
                      View{"ReciprocatingSaw/ReciprocatingSaw.gltf", "walk:16", 256, true},
                      View{"ReciprocatingSaw/ReciprocatingSaw.gltf", "orbit:16", 512, true},
                      View{"2CylinderEngine/2CylinderEngine.gltf", "walk:16", 256, true},
                      View{"2CylinderEngine/2CylinderEngine.gltf", "orbit:16", 512, true},
                      View{"sponza_lod4/sponza_s_lod4.glb", "walk:16", 256, true},
                      View{"sponza_lod4/sponza_s_lod4.glb", "orbit:16", 512, true}));

}  // namespace

// The bridge's bars lie inside its concrete with 3.75 cm to spare, yet brute force shows a few
// pixels of them through it: llvmpipe's depth of a bar's side faces, slivers thousands of times
// longer than wide on screen, can be off by 1e-4..1e-3 of the distance (docs/hard_cases.md). HC
// skips sealed bars (found at start-up), so the switch's frames differ from brute force's there,
// and only there: every differing pixel is one where brute force's item buffer shows a sealed item.
TEST(Sealed, TheSwitchDiffersFromBruteForceOnlyWhereBruteForceShowsASealedBar) {
  const std::string spec = "bridge:6", path = "orbit:20";
  const fs::path dir = fresh_dir("sealed");
  const std::vector<std::string> view = {"--width", "512", "--height", "512"};
  auto with = [&](std::vector<std::string> f) {
    f.insert(f.end(), view.begin(), view.end());
    return f;
  };
  const Outcome none = run_reference(dir / "none", spec, path, with({"--cull", "none", "--images", "png+items"}));
  ASSERT_EQ(none.code, 0) << none.log;
  occ::Scene scene = occ::load_scene(spec);
  const occ::Hierarchy h = occ::Hierarchy::build(scene, {});
  const occ::Enclosures sealed = occ::Enclosures::find(scene, h);
  ASSERT_GT(sealed.sealed_items(), h.items().size() / 2);
  ::setenv("OCC_BIN", OCC_BIN_DIR, 1);
  {
    const fs::path out = dir / "sealed";
    const Outcome o = run_to_end(with({"/bin/bash", std::string(OCC_SOURCE_DIR) + "/scripts/cluster.sh", "--scene", spec,
                                       "--path", path, "--out", out.string()}),
                                 dir / "sealed.log", 300s);
    ASSERT_EQ(o.code, 0) << o.log;
    uint64_t differing = 0;
    for (int f = 0; f < 20; ++f) {
      char name[32];
      std::snprintf(name, sizeof name, "%05d.png", f);
      const occ::Image a = occ::read_png((dir / "none" / (std::string("frame_") + name)).string());
      const occ::Image b = occ::read_png((out / (std::string("frame_") + name)).string());
      const occ::Image items = occ::read_png((dir / "none" / (std::string("items_") + name)).string());
      ASSERT_EQ(a.rgba.size(), b.rgba.size());
      for (size_t p = 0; p + 3 < a.rgba.size(); p += 4) {
        if (std::equal(&a.rgba[p], &a.rgba[p] + 4, &b.rgba[p])) continue;
        ++differing;
        uint32_t id = 0;
        std::memcpy(&id, &items.rgba[p], 4);  // item index + 1 (0: background)
        ASSERT_TRUE(id >= 1 && id <= h.items().size()) << "frame " << f << " pixel " << p / 4 << ": id " << id;
        uint32_t leaf = 0;
        for (uint32_t n = 0; n < h.size(); ++n)
          if (h.node(n).leaf() && h.node(n).first_item == id - 1) leaf = n;
        EXPECT_TRUE(sealed.sealed(leaf)) << "frame " << f << ", pixel " << p / 4 << ": "
                                         << scene.objects[h.items()[id - 1].object].name << " is not sealed";
      }
    }
    std::cout << differing << " pixels differ from brute force, all of sealed bars\n";
  }
}
