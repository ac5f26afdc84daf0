// Cracks between meshes (issue 33): hard:cracks builds walls and slabs as separate meshes that
// abut (T-junctions, vertices that do not match) or leave seams of 0.5 to 24 mm (0.03 to 3 pixels),
// with cubes of 2 to 10 mm right behind the seams and a field of 3 mm cubes: the pixels real
// building exports got wrong. Every culling method must draw brute force's frames exactly, at
// 256^2, 512^2 and 1024^2, and far from the origin: CHC and stop-and-wait (one process), the
// switch (three processes), the switch's frustum sets culled by the render client in two passes,
// and the depth-readback occlusion server (GigaWalk).
#include <gtest/gtest.h>

#include "integration_util.hpp"

using namespace occtest;
using namespace std::chrono_literals;

namespace {

struct CrackView {
  const char* scene;
  const char* path;
  int size;  // viewport size x size
};
void PrintTo(const CrackView& v, std::ostream* os) { *os << v.scene << " " << v.path << " " << v.size; }

void expect_identical(const fs::path& reference, const fs::path& frames, const std::string& what) {
  const Outcome d = frame_diff(reference, frames, {"--max-fraction", "0"});
  EXPECT_EQ(d.code, 0) << what << ": " << diff_summary(d.log);
  EXPECT_NE(diff_summary(d.log).find("differing_pixels=0 "), std::string::npos) << what << ": " << d.log;
}

class Cracks : public ::testing::TestWithParam<CrackView> {};

TEST_P(Cracks, EveryMethodDrawsBruteForcesFrames) {
  const CrackView v = GetParam();
  const fs::path dir = fresh_dir("cracks");
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
           {"switch", {}}, {"two_pass", {"--occlusion-gate", "off", "--two-pass", "on"}}}) {
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

INSTANTIATE_TEST_SUITE_P(Views, Cracks,
                         ::testing::Values(CrackView{"hard:cracks", "walk:40", 256},
                                           CrackView{"hard:cracks", "walk:40", 512},
                                           CrackView{"hard:cracks", "walk:24", 1024},
                                           CrackView{"hard:cracks", "orbit:24", 512},
                                           CrackView{"offset:1e5,0,-3e4:hard:cracks", "walk:40", 512}));

}  // namespace
