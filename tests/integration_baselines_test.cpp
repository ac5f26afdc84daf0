// The single-process baselines are conservative too: their frames equal the unculled reference,
// and the exact visible set (item buffer) never exceeds what they draw.
#include <gtest/gtest.h>

#include "integration_util.hpp"

using namespace occtest;
using namespace std::chrono_literals;

namespace {
const std::vector<std::string> kView = {"--width", "160", "--height", "120"};

// The single-process renderer with culling `cull` on the city walk (40 frames) into `out`.
Outcome render(const fs::path& out, const std::string& cull, bool exact) {
  std::vector<std::string> flags = kView;
  flags.insert(flags.end(), {"--cull", cull});
  if (exact) flags.push_back("--exact");
  return run_reference(out, "city:6x6:3:10:1", "walk:40", flags, 120s);
}
}  // namespace

TEST(Baselines, StopAndWaitAndChcFramesEqualTheUnculledReference) {
  fs::path dir = fresh_dir("baselines");
  const Outcome none = render(dir / "none", "none", true);
  ASSERT_EQ(none.code, 0) << none.log;
  for (const char* cull : {"stop-and-wait", "chc"}) {
    const Outcome culled = render(dir / cull, cull, false);
    ASSERT_EQ(culled.code, 0) << culled.log;
    const Outcome diff = frame_diff(dir / "none", dir / cull);
    EXPECT_EQ(diff.code, 0) << cull << ": " << differing_frames(diff.log);
    auto st = read_csv(dir / cull / "stats.csv");
    auto ex = read_csv(dir / "none" / "stats.csv");
    ASSERT_EQ(st["nodes_drawn"].size(), 40u);
    for (size_t f = 0; f < 40; ++f) EXPECT_GE(st["nodes_drawn"][f], ex["exact_visible"][f]) << cull << " frame " << f;
    EXPECT_GT(sum(st["queries"]), 0);
    EXPECT_LT(sum(st["nodes_drawn"]), sum(ex["nodes_drawn"]));  // and they do cull
  }
}

TEST(Baselines, DepthReadbackOcclusionServerFramesEqualTheReference) {
  fs::path dir = fresh_dir("gigawalk");
  ASSERT_EQ(render(dir / "ref", "frustum", false).code, 0);
  fs::path out = dir / "server";
  fs::create_directories(out);
  Proc server({bin("occlusion_server"), "--scene", "city:6x6:3:10:1", "--width", "160", "--height", "120",
               "--port-file", (out / "port").string(), "--timeout-ms", "20000"},
              out / "server.log");
  int port = wait_port(out / "port", server);
  ASSERT_NE(port, 0) << server.log();
  Proc rvg({bin("render_client"), "--scene", "city:6x6:3:10:1", "--path", "walk:40", "--width", "160", "--height",
            "120", "--connect", "127.0.0.1:" + std::to_string(port), "--out", out.string()},
           out / "client.log");
  ASSERT_EQ(rvg.wait(120s), 0) << rvg.log();
  EXPECT_EQ(server.wait(30s), 0) << server.log();
  const Outcome diff = frame_diff(dir / "ref", out);
  EXPECT_EQ(diff.code, 0) << differing_frames(diff.log);
  auto st = read_csv(out / "stats.csv");
  ASSERT_EQ(st["frame"].size(), 40u);
  EXPECT_LT(sum(st["visible"]) / 40, 0.5 * 360);  // it culls
}
