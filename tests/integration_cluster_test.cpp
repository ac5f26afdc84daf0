// The occlusion switch end to end: three real processes over loopback, compared with the
// reference renderer frame by frame (conservative culling must not change a pixel).
#include <gtest/gtest.h>

#include "integration_util.hpp"

using namespace occtest;
using namespace std::chrono_literals;

namespace {

const std::vector<std::string> kView = {"--width", "192", "--height", "144"};

struct ClusterRun {
  int rvg_code = -1, node0_code = -1, node1_code = -1;
  std::string rvg_log, node0_log, node1_log;
};

// Starts node 0, node 1 and the render client like scripts/cluster.sh does.
ClusterRun run_cluster(const fs::path& out, const std::string& scene, const std::string& path,
                       std::vector<std::string> extra = {}, std::vector<std::string> rvg_extra = {},
                       std::vector<std::string> node_extra = {},
                       std::chrono::milliseconds timeout = 300s) {
  fs::create_directories(out);
  std::vector<std::string> common = {"--scene", scene, "--timeout-ms", "20000"};
  common.insert(common.end(), kView.begin(), kView.end());
  common.insert(common.end(), extra.begin(), extra.end());
  auto args = [&](std::vector<std::string> a, const std::vector<std::string>& more = {}) {
    a.insert(a.end(), common.begin(), common.end());
    a.insert(a.end(), more.begin(), more.end());
    return a;
  };
  Proc n0(args({bin("switch_node"), "--id", "0", "--port-file", (out / "n0.port").string()}, node_extra),
          out / "node0.log");
  int p0 = wait_port(out / "n0.port", n0);
  Proc n1(args({bin("switch_node"), "--id", "1", "--peer", "127.0.0.1:" + std::to_string(p0), "--port-file",
                (out / "n1.port").string()}, node_extra),
          out / "node1.log");
  int p1 = wait_port(out / "n1.port", n1);
  ClusterRun r;
  if (p0 && p1) {
    Proc rvg(args({bin("render_client"), "--path", path, "--out", out.string(), "--connect",
                   "127.0.0.1:" + std::to_string(p0), "--connect", "127.0.0.1:" + std::to_string(p1)}, rvg_extra),
             out / "render_client.log");
    r.rvg_code = rvg.wait(timeout);
    r.rvg_log = rvg.log();
  }
  r.node0_code = n0.wait(30s);
  r.node1_code = n1.wait(30s);
  r.node0_log = n0.log();
  r.node1_log = n1.log();
  return r;
}

int run_reference(const fs::path& out, const std::string& scene, const std::string& path) {
  fs::create_directories(out);
  std::vector<std::string> a = {bin("render_client"), "--reference", "--scene", scene, "--path", path, "--out", out.string()};
  a.insert(a.end(), kView.begin(), kView.end());
  Proc p(a, out / "reference.log");
  return p.wait(300s);
}

// frame_diff exit code; its last line in *summary.
int frame_diff(const fs::path& a, const fs::path& b, std::string* summary) {
  Proc p({bin("frame_diff"), a.string(), b.string(), "--max-fraction", "0.0001"}, a / "diff.log");
  int code = p.wait(120s);
  std::string log = p.log();
  size_t last = log.rfind("frames=");
  *summary = last == std::string::npos ? log : log.substr(last);
  return code;
}

void expect_cluster_equals_reference(const std::string& name, const std::string& scene, const std::string& path,
                                     size_t frames, bool coherent) {
  fs::path dir = fresh_dir(name);
  ClusterRun r = run_cluster(dir / "cluster", scene, path);
  ASSERT_EQ(r.rvg_code, 0) << r.rvg_log << r.node0_log << r.node1_log;
  EXPECT_EQ(r.node0_code, 0) << r.node0_log;
  EXPECT_EQ(r.node1_code, 0) << r.node1_log;
  ASSERT_EQ(run_reference(dir / "reference", scene, path), 0) << read_file(dir / "reference" / "reference.log");
  std::string summary;
  EXPECT_EQ(frame_diff(dir / "reference", dir / "cluster", &summary), 0) << summary;
  EXPECT_NE(summary.find("frames=" + std::to_string(frames)), std::string::npos) << summary;

  // Every frame arrived and verified (the client exits non-zero on a desync), and culling culled.
  auto stats = read_csv(dir / "cluster" / "stats.csv");
  ASSERT_EQ(stats["frame"].size(), frames);
  size_t leaves = 0;
  auto pos = r.rvg_log.find("leaves=");
  ASSERT_NE(pos, std::string::npos);
  leaves = std::stoul(r.rvg_log.substr(pos + 7));
  // From frame 2 on the occluders are the previous visible set (frame 0 has none).
  std::vector<double> warm(stats["visible"].begin() + 2, stats["visible"].end());
  EXPECT_LT(sum(warm) / warm.size(), 0.5 * leaves);
  // Incremental transmission: the diff ids sent are fewer than the visible sets they describe.
  // (Not on a walk through walls: each wall crossing empties and refills the set.)
  if (coherent) {
    EXPECT_LT(sum(stats["added"]) + sum(stats["removed"]), sum(stats["visible"]));
  }
  for (double q : stats["queries"]) EXPECT_GT(q, 0);
}

}  // namespace

TEST(Cluster, CityWalkEqualsReference) {
  expect_cluster_equals_reference("city", "city:6x6:3:10:1", "walk:90", 90, true);
}

// Unique geometry (every object its own mesh): the plant's aisle walk, pipes crossing overhead.
TEST(Cluster, PlantWalkEqualsReference) {
  expect_cluster_equals_reference("plant", "plant:0.3", "walk:40", 40, true);
}

TEST(Cluster, DuplexWalkEqualsReference) {
  if (!have_shared()) GTEST_SKIP() << "../shared/scenes not found: the duplex test needs it";
  expect_cluster_equals_reference("duplex", shared("scenes/duplex/Duplex_A_20110505.gltf"), "walk:60", 60, false);
}

TEST(Cluster, IncrementalDiffsUseFewerBytesThanFullSets) {
  fs::path dir = fresh_dir("fullsets");
  // Adaptive queries and occluder fusion off: with them the set may keep assumed-visible nodes or
  // depend on what was drawn before each query, and full sets turn front tracking off, so the two
  // traversals (both conservative) would differ slightly.
  const std::vector<std::string> exact_queries = {"--adaptive-queries", "off", "--occluder-fusion", "off"};
  ClusterRun inc = run_cluster(dir / "inc", "city:6x6:3:10:1", "walk:90", {}, {"--no-images"}, exact_queries);
  ClusterRun full =
      run_cluster(dir / "full", "city:6x6:3:10:1", "walk:90", {"--full-sets"}, {"--no-images"}, exact_queries);
  ASSERT_EQ(inc.rvg_code, 0) << inc.rvg_log;
  ASSERT_EQ(full.rvg_code, 0) << full.rvg_log;
  auto a = read_csv(dir / "inc" / "stats.csv"), b = read_csv(dir / "full" / "stats.csv");
  EXPECT_EQ(a["visible"], b["visible"]);  // same sets either way
  EXPECT_LT(sum(a["bytes_received"]), sum(b["bytes_received"]));
}

TEST(ClusterFaults, KilledSwitchNodeIsReportedWithNodeAndFrameAndNoPartialImage) {
  fs::path dir = fresh_dir("kill");
  fs::path out = dir / "cluster";
  fs::create_directories(out);
  std::vector<std::string> common = {"--scene", "city:6x6:3:10:1", "--timeout-ms", "20000"};
  common.insert(common.end(), kView.begin(), kView.end());
  auto args = [&](std::vector<std::string> a) {
    a.insert(a.end(), common.begin(), common.end());
    return a;
  };
  Proc n0(args({bin("switch_node"), "--id", "0", "--port-file", (out / "n0.port").string()}), out / "node0.log");
  int p0 = wait_port(out / "n0.port", n0);
  Proc n1(args({bin("switch_node"), "--id", "1", "--peer", "127.0.0.1:" + std::to_string(p0), "--port-file",
                (out / "n1.port").string()}),
          out / "node1.log");
  int p1 = wait_port(out / "n1.port", n1);
  ASSERT_TRUE(p0 && p1);
  Proc rvg(args({bin("render_client"), "--path", "walk:100000", "--out", out.string(), "--connect",
                 "127.0.0.1:" + std::to_string(p0), "--connect", "127.0.0.1:" + std::to_string(p1)}),
           out / "render_client.log");
  // Kill node 1 once frames are flowing.
  for (int i = 0; i < 500 && read_csv(out / "stats.csv")["frame"].size() < 20; ++i) std::this_thread::sleep_for(20ms);
  ASSERT_GE(read_csv(out / "stats.csv")["frame"].size(), 20u) << rvg.log();
  n1.kill_now();
  const auto t0 = std::chrono::steady_clock::now();
  int code = rvg.wait(30s);
  const double waited_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::string log = rvg.log();
  EXPECT_EQ(code, 1) << log;
  EXPECT_LT(waited_s, 20.0);  // ended by the disconnect, not by the 20 s timeout
  EXPECT_NE(log.find("error: render_client: frame "), std::string::npos) << log;
  EXPECT_NE(log.find("switch node 1"), std::string::npos) << log;
  // Node 0 ends too, not hanging: with an error if it noticed node 1's death first, cleanly if
  // the render client's goodbye (which says it failed) came first.
  const int n0_code = n0.wait(30s);
  EXPECT_TRUE(n0_code == 0 || n0_code == 1) << n0.log();
  EXPECT_NE(n0.log().find(n0_code == 1 ? "switch node 1" : "render client failed"), std::string::npos) << n0.log();
  // Every frame file is complete and has its stats row: nothing partial was written.
  size_t pngs = 0;
  for (auto& e : fs::directory_iterator(out)) {
    std::string name = e.path().filename().string();
    EXPECT_EQ(name.find(".tmp"), std::string::npos) << name;
    pngs += name.rfind("frame_", 0) == 0;
  }
  EXPECT_EQ(pngs, read_csv(out / "stats.csv")["frame"].size());
}

TEST(ClusterFaults, SceneFingerprintMismatchIsRefusedAtHandshakeNamingBoth) {
  fs::path out = fresh_dir("fingerprint");
  Proc n0({bin("switch_node"), "--id", "0", "--scene", "city:4x4:2:5:1", "--timeout-ms", "3000", "--port-file",
           (out / "n0.port").string(), "--width", "64", "--height", "64"},
          out / "node0.log");
  int p0 = wait_port(out / "n0.port", n0);
  ASSERT_NE(p0, 0) << n0.log();
  Proc n1({bin("switch_node"), "--id", "1", "--scene", "city:5x4:2:5:1", "--timeout-ms", "3000", "--peer",
           "127.0.0.1:" + std::to_string(p0), "--width", "64", "--height", "64"},
          out / "node1.log");
  EXPECT_EQ(n1.wait(30s), 1);
  EXPECT_EQ(n0.wait(30s), 1);  // never got a valid peer
  std::string l1 = n1.log(), l0 = n0.log();
  auto fingerprint_of = [](const std::string& log) {
    auto p = log.find("fingerprint ");
    return p == std::string::npos ? std::string("?") : log.substr(p + 12, 16);
  };
  std::string f0 = fingerprint_of(l0), f1 = fingerprint_of(l1);
  ASSERT_NE(f0, f1);
  EXPECT_NE(l1.find("fingerprint mismatch"), std::string::npos) << l1;
  EXPECT_NE(l1.find(f0), std::string::npos) << l1;
  EXPECT_NE(l1.find(f1), std::string::npos) << l1;
  EXPECT_NE(l0.find("fingerprint mismatch"), std::string::npos) << l0;
}

TEST(Cluster, LatestCameraModeRunsToTheLastCameraWithVerifiedFrames) {
  fs::path dir = fresh_dir("latest");
  ClusterRun r = run_cluster(dir, "city:6x6:3:10:1", "walk:40", {"--camera-mode", "latest"}, {"--no-images"});
  ASSERT_EQ(r.rvg_code, 0) << r.rvg_log;
  EXPECT_EQ(r.node0_code, 0) << r.node0_log;
  EXPECT_EQ(r.node1_code, 0) << r.node1_log;
  auto stats = read_csv(dir / "stats.csv");
  ASSERT_FALSE(stats["camera"].empty());
  EXPECT_EQ(stats["camera"].back(), 39);
  // The two nodes pick their cameras independently: when the newest camera reaches one node a
  // moment before the other, a frame may use the camera just before the previous frame's. Never
  // more than that, and every frame's set was verified (the client exits non-zero otherwise).
  for (size_t i = 1; i < stats["camera"].size(); ++i) EXPECT_GE(stats["camera"][i], stats["camera"][i - 1] - 1);
}

// Levels of detail (tau > 0): every process verifies every frame (set hash and front hash), the
// LOD cache is built once and reused, fewer triangles are drawn than at tau = 0, and the image
// stays close to the full-detail reference.
TEST(ClusterLod, PixelErrorWalkVerifiesOnAllProcessesAndStaysCloseToReference) {
  fs::path dir = fresh_dir("lod");
  const std::string scene = "city:6x6:3:10:1", path = "walk:60";
  const std::vector<std::string> cache = {"--lod-cache", (dir / "cache").string()};
  auto with = [&](std::vector<std::string> a) {
    a.insert(a.end(), cache.begin(), cache.end());
    return a;
  };
  ClusterRun exact = run_cluster(dir / "tau0", scene, path, with({}), {"--no-images"});
  ASSERT_EQ(exact.rvg_code, 0) << exact.rvg_log;
  ClusterRun r = run_cluster(dir / "tau3", scene, path, with({"--pixel-error", "3"}));
  ASSERT_EQ(r.rvg_code, 0) << r.rvg_log << r.node0_log << r.node1_log;
  EXPECT_EQ(r.node0_code, 0) << r.node0_log;
  EXPECT_EQ(r.node1_code, 0) << r.node1_log;
  // Node 0 built the cache, node 1 and the render client loaded it; all agree on the fingerprint.
  EXPECT_NE(r.node0_log.find("built LODs"), std::string::npos) << r.node0_log;
  EXPECT_NE(r.node1_log.find("LOD cache"), std::string::npos) << r.node1_log;
  EXPECT_NE(r.rvg_log.find("loaded in"), std::string::npos) << r.rvg_log;
  auto fp = [](const std::string& log) {
    auto p = log.find("fingerprint with LODs ");
    return p == std::string::npos ? std::string("?") : log.substr(p + 22, 16);
  };
  EXPECT_EQ(fp(r.node0_log), fp(r.rvg_log));
  EXPECT_EQ(fp(r.node1_log), fp(r.rvg_log));
  EXPECT_NE(fp(r.rvg_log), "?");
  auto a = read_csv(dir / "tau0" / "stats.csv"), b = read_csv(dir / "tau3" / "stats.csv");
  ASSERT_EQ(b["frame"].size(), 60u);
  EXPECT_LT(sum(b["triangles"]), 0.8 * sum(a["triangles"]));
  EXPECT_NE(r.node0_log.find("front tracking skipped"), std::string::npos);
  // Close to full detail: few differing pixels (LOD is not exact, so not zero).
  ASSERT_EQ(run_reference(dir / "reference", scene, path), 0);
  Proc diff({bin("frame_diff"), (dir / "reference").string(), (dir / "tau3").string(), "--threshold", "16",
             "--max-fraction", "0.05", "--psnr"},
            dir / "diff.log");
  EXPECT_EQ(diff.wait(120s), 0) << diff.log();
  EXPECT_NE(diff.log().find("psnr_db="), std::string::npos) << diff.log();
}

TEST(ClusterLod, VisiblePixelLodAndNoFrontTrackingRunVerified) {
  fs::path dir = fresh_dir("lodvp");
  const std::vector<std::string> cache = {"--lod-cache", (dir / "cache").string()};
  for (auto extra : std::vector<std::vector<std::string>>{{"--pixel-error", "5", "--visible-pixel-lod", "on"},
                                                          {"--pixel-error", "5", "--front-tracking", "off"}}) {
    extra.insert(extra.end(), cache.begin(), cache.end());
    const fs::path out = dir / extra[3];
    ClusterRun r = run_cluster(out, "city:6x6:3:10:1", "walk:40", extra, {"--no-images"});
    ASSERT_EQ(r.rvg_code, 0) << r.rvg_log << r.node0_log << r.node1_log;
    EXPECT_EQ(r.node0_code, 0) << r.node0_log;
    EXPECT_EQ(r.node1_code, 0) << r.node1_log;
    EXPECT_EQ(read_csv(out / "stats.csv")["frame"].size(), 40u);
  }
}

TEST(ClusterLod, MismatchedPixelErrorIsRefusedAtHandshake) {
  fs::path out = fresh_dir("lodmismatch");
  const std::vector<std::string> common = {"--scene", "city:4x4:2:5:1", "--timeout-ms", "3000", "--width", "64",
                                           "--height", "64", "--lod-cache", (out / "cache").string()};
  std::vector<std::string> a0 = {bin("switch_node"), "--id", "0", "--pixel-error", "1", "--port-file",
                                 (out / "n0.port").string()};
  a0.insert(a0.end(), common.begin(), common.end());
  Proc n0(a0, out / "node0.log");
  int p0 = wait_port(out / "n0.port", n0);
  ASSERT_NE(p0, 0) << n0.log();
  std::vector<std::string> a1 = {bin("switch_node"), "--id", "1", "--pixel-error", "2", "--peer",
                                 "127.0.0.1:" + std::to_string(p0)};
  a1.insert(a1.end(), common.begin(), common.end());
  Proc n1(a1, out / "node1.log");
  EXPECT_EQ(n1.wait(30s), 1);
  EXPECT_EQ(n0.wait(30s), 1);
  EXPECT_NE(n1.log().find("config hash"), std::string::npos) << n1.log();
}
