// The single-process baselines are conservative too: their frames equal the unculled reference,
// and the exact visible set (item buffer) never exceeds what they draw.
#include <gtest/gtest.h>

#include "integration_util.hpp"

using namespace occtest;
using namespace std::chrono_literals;

namespace {
int render(const fs::path& out, const std::string& cull, bool exact) {
  fs::create_directories(out);
  std::vector<std::string> a = {bin("render_client"), "--reference", "--scene", "city:6x6:3:10:1", "--path", "walk:40",
                                "--width", "160", "--height", "120", "--cull", cull, "--out", out.string()};
  if (exact) a.push_back("--exact");
  Proc p(a, out / "log.txt");
  return p.wait(120s);
}
}  // namespace

TEST(Baselines, StopAndWaitAndChcFramesEqualTheUnculledReference) {
  fs::path dir = fresh_dir("baselines");
  ASSERT_EQ(render(dir / "none", "none", true), 0) << read_file(dir / "none" / "log.txt");
  for (const char* cull : {"stop-and-wait", "chc"}) {
    ASSERT_EQ(render(dir / cull, cull, false), 0) << read_file(dir / cull / "log.txt");
    Proc diff({bin("frame_diff"), (dir / "none").string(), (dir / cull).string(), "--max-fraction", "0.0001"},
              dir / (std::string(cull) + "_diff.log"));
    EXPECT_EQ(diff.wait(60s), 0) << cull << ": " << diff.log();
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
  ASSERT_EQ(render(dir / "ref", "frustum", false), 0);
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
  Proc diff({bin("frame_diff"), (dir / "ref").string(), out.string(), "--max-fraction", "0.0001"}, dir / "diff.log");
  EXPECT_EQ(diff.wait(60s), 0) << diff.log();
  auto st = read_csv(out / "stats.csv");
  ASSERT_EQ(st["frame"].size(), 40u);
  EXPECT_LT(sum(st["visible"]) / 40, 0.5 * 360);  // it culls
}
