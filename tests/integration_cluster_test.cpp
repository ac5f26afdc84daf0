// The occlusion switch end to end: three real processes over loopback, compared with the
// reference renderer frame by frame (conservative culling must not change a pixel).
#include <cmath>
#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <map>
#include <regex>
#include <sstream>

#include "cluster_run.hpp"

using namespace occtest;
using namespace std::chrono_literals;

namespace {

const std::vector<std::string> kView = {"--width", "192", "--height", "144"};
const std::vector<std::string> kSmallView = {"--width", "64", "--height", "64"};
const std::string kCity = "city:6x6:3:10:1";

ClusterOptions cluster(const std::string& scene, const std::string& path) {
  return ClusterOptions(scene, path, kView);
}

// The number written right before the first `phrase` at or after `from` in a log ("..., 12 proven
// occluded"), or -1 where there is none.
long number_before(const std::string& log, const std::string& phrase, size_t from = 0) {
  const size_t at = log.find(phrase, from);
  if (at == std::string::npos) return -1;
  size_t begin = at;
  while (begin > 0 && std::isdigit(static_cast<unsigned char>(log[begin - 1]))) --begin;
  return begin == at ? -1 : std::stol(log.substr(begin, at - begin));
}

// The boxes each node's summary says its back end tested ("occlusion back end B: N boxes tested"),
// summed over both nodes, are the boxes of the HC frames the render client logged (stats.csv
// queries: each EndOfFrame's): the summary counts what the back end did, and nothing else.
void expect_summaries_count_the_boxes_tested(const ClusterRun& r, const fs::path& stats_csv) {
  auto stats = read_csv(stats_csv);
  long summaries = 0;
  for (const std::string* log : {&r.node0_log, &r.node1_log}) {
    const size_t line = log->find(": occlusion back end ");  // the summary's (the start-up's has "end:")
    ASSERT_NE(line, std::string::npos) << *log;
    const long n = number_before(*log, " boxes tested (", line);
    ASSERT_GE(n, 0) << log->substr(line, 300);
    summaries += n;
  }
  EXPECT_GT(summaries, 0);
  EXPECT_EQ(double(summaries), sum(stats["queries"])) << "boxes tested by the nodes' summaries and the frames' EndOfFrames";
}

void expect_cluster_equals_reference(const std::string& name, const std::string& scene, const std::string& path,
                                     size_t frames, bool coherent) {
  fs::path dir = fresh_dir(name);
  const std::optional<ClusterRun> r = expect_cluster_equals_reference(dir, cluster(scene, path), kView, frames);
  if (!r) return;

  // Every frame arrived and verified (the client exits non-zero on a desync), and culling culled.
  auto stats = read_csv(dir / "cluster" / "stats.csv");
  ASSERT_EQ(stats["frame"].size(), frames);
  size_t leaves = 0;
  auto pos = r->rvg_log.find("leaves=");
  ASSERT_NE(pos, std::string::npos);
  leaves = std::stoul(r->rvg_log.substr(pos + 7));
  // From frame 2 on the occluders are the previous visible set (frame 0 has none).
  std::vector<double> warm(stats["visible"].begin() + 2, stats["visible"].end());
  EXPECT_LT(sum(warm) / warm.size(), 0.5 * leaves);
  // Incremental transmission: the diff ids sent are fewer than the visible sets they describe.
  // (Not on a walk through walls: each wall crossing empties and refills the set.)
  if (coherent) {
    EXPECT_LT(sum(stats["added"]) + sum(stats["removed"]), sum(stats["visible"]));
  }
  // HC queried: in every early frame (adaptive queries then trust nodes that keep passing: a
  // late frame of a walk may need none).
  for (size_t f = 0; f < std::min<size_t>(frames, 10); ++f) EXPECT_GT(stats["queries"][f], 0) << "frame " << f;
  expect_summaries_count_the_boxes_tested(*r, dir / "cluster" / "stats.csv");
  // The wait for a frame's set is part of the interval since the frame before (stats.csv wait_ms).
  ASSERT_EQ(stats["wait_ms"].size(), frames);
  for (size_t f = 1; f < frames; ++f) {
    EXPECT_GE(stats["wait_ms"][f], 0.0) << "frame " << f;
    EXPECT_LE(stats["wait_ms"][f], stats["frame_interval_ms"][f] + 0.01) << "frame " << f;  // the CSV's rounding
  }
}

// The plant's 40-camera walk (`o`: cluster("plant:0.3", "walk:40")) with the render client's
// --occlusion `policy`, frames checked against the reference; the run's stats (40 rows) in
// `stats`. Null when the cluster run failed.
std::optional<ClusterRun> plant_walk_with_gate(const fs::path& dir, const std::string& policy, ClusterOptions& o,
                                               std::map<std::string, std::vector<double>>& stats) {
  o.occlusion = policy;
  std::optional<ClusterRun> r = expect_cluster_equals_reference(dir, o, kView, 40);
  if (!r) return r;
  stats = read_csv(dir / "cluster" / "stats.csv");
  EXPECT_EQ(stats["occlusion"].size(), 40u);
  if (stats["occlusion"].size() != 40u) return std::nullopt;
  return r;
}

// How long node 0 waits for a valid peer in the handshake tests (then exits 1, which they expect):
// node 1 must start (scene, GL) and connect within it, seconds on a loaded machine under ASan.
constexpr int kRefusalTimeoutMs = 10000;

// Two switch nodes and no client, both refusing each other at the handshake (exit 1): their logs
// (nothing when node 0 did not start).
struct Refused {
  std::string node0_log, node1_log;
};
std::optional<Refused> expect_handshake_refused(const fs::path& out, const ClusterOptions& o) {
  Cluster c(out, o);
  const int p0 = c.start_node0();
  EXPECT_NE(p0, 0) << c.node0().log();
  if (p0 == 0) return std::nullopt;
  c.start_node1();
  EXPECT_EQ(c.node1().wait(30s), 1);
  EXPECT_EQ(c.node0().wait(30s), 1);  // never got a valid peer
  return Refused{c.node0().log(), c.node1().log()};
}

}  // namespace

TEST(Cluster, CityWalkEqualsReference) {
  expect_cluster_equals_reference("city", kCity, "walk:90", 90, true);
}

// Unique geometry (every object its own mesh): the plant's aisle walk, pipes crossing overhead.
TEST(Cluster, PlantWalkEqualsReference) {
  expect_cluster_equals_reference("plant", "plant:0.3", "walk:40", 40, true);
}

// HC with the GPU depth pyramid in front of the queries (--backend gpu-pyramid, what a hardware
// GPU would choose besides plain queries) on both nodes draws the reference's frames, and the
// pyramid did prove boxes occluded on both nodes.
TEST(Cluster, PlantWalkWithDepthPyramidHcEqualsReference) {
  fs::path dir = fresh_dir("plant_pyramid");
  ClusterOptions o = cluster("plant:0.3", "walk:40");
  o.node0 = o.node1 = {"--backend", "gpu-pyramid"};
  const std::optional<ClusterRun> r = expect_cluster_equals_reference(dir, o, kView, 40);
  if (!r) return;
  expect_summaries_count_the_boxes_tested(*r, dir / "cluster" / "stats.csv");
  for (const std::string* log : {&r->node0_log, &r->node1_log}) {
    EXPECT_NE(log->find("occlusion back end: gpu-pyramid (--backend gpu-pyramid;"), std::string::npos) << *log;
    const size_t at = log->find("occlusion back end gpu-pyramid: ");
    ASSERT_NE(at, std::string::npos) << *log;
    EXPECT_GT(number_before(*log, " proven occluded by the depth pyramid", at), 0) << log->substr(at, 300);
  }
}

// Occlusion only where it pays: the render client's gate switches frames between the
// switch with occlusion and frustum sets (no OR, no queries on the HC node). --occlusion
// alternate:4 switches every 4 cameras, so both changes of mode happen many times: the frames
// stay the reference's; frames without occlusion issued no queries and drew at least the frustum
// set's leaves; both nodes served some of them. The render client culls those frustum sets
// itself in two passes (4 of them each way in turn), hiding leaves behind the aisle's walls.
TEST(Cluster, FramesWithAndWithoutOcclusionInTurnEqualReference) {
  ClusterOptions o = cluster("plant:0.3", "walk:40");
  std::map<std::string, std::vector<double>> stats;
  const std::optional<ClusterRun> r = plant_walk_with_gate(fresh_dir("plant_gate"), "alternate:4", o, stats);
  if (!r) return;
  size_t with = 0, without = 0, visible_with = 0, visible_without = 0, two_pass = 0, hidden = 0;
  for (size_t f = 0; f < 40; ++f) {
    EXPECT_EQ(stats["occlusion"][f], (uint32_t(stats["camera"][f]) / 4) % 2 == 0 ? 1.0 : 0.0) << "frame " << f;
    if (stats["occlusion"][f] != 0) {
      ++with;
      visible_with += size_t(stats["visible"][f]);
      EXPECT_EQ(stats["two_pass"][f], 0.0) << "frame " << f << ": the switch culled it";
      continue;
    }
    EXPECT_EQ(stats["two_pass"][f] != 0, (without / 4) % 2 == 0) << "frame " << f << " (frustum set " << without << ")";
    two_pass += stats["two_pass"][f] != 0;
    hidden += size_t(stats["hidden_here"][f]);
    ++without;
    visible_without += size_t(stats["visible"][f]);
    EXPECT_EQ(stats["queries"][f], 0.0) << "frame " << f;
  }
  EXPECT_EQ(with, 20u);
  EXPECT_EQ(without, 20u);
  EXPECT_EQ(two_pass, 12u);
  EXPECT_GT(hidden, 0u) << "the render client's own culling hid leaves of the frustum sets";
  EXPECT_GT(visible_without, visible_with);  // the aisle's walls hide most of the plant
  // Each of the four changes to occlusion (cameras 8, 16, 24, 32) starts from a frustum set:
  // the first OR after it draws none (HC culls it nearest first), nor does the second, which
  // draws the first's culled set once its stream is in.
  uint64_t ors = 0;
  for (const std::string* log : {&r->node0_log, &r->node1_log}) {
    const size_t at = log->find("; 10 frames without occlusion (the render client's gate; ");
    ASSERT_NE(at, std::string::npos) << *log;
    ors += std::stoul(log->substr(at + std::string("; 10 frames without occlusion (the render client's gate; ").size()));
  }
  EXPECT_EQ(ors, 8u);
}

// Where the CPU back end cannot work (here: plant:M streams its geometry within --geometry-budget,
// so its triangles are not on the CPU) the default on llvmpipe is cpu-pyramid (a depth pyramid
// read back to the CPU decides what it can, the rest are counted by one draw per batch);
// occlusion queries stay available. Node 0 with --backend queries, node 1 with the default: the
// reference's frames, node 0 drew no batch and node 1 proved boxes on the CPU and counted others
// in batch draws.
TEST(Cluster, PlantWalkWithQueriesOnNode0AndDefaultCpuPyramidOnNode1EqualsReference) {
  fs::path dir = fresh_dir("plant_queries_batch");
  ClusterOptions o = cluster("plant:0.3", "walk:40");
  o.node0 = {"--backend", "queries"};
  const std::optional<ClusterRun> r = expect_cluster_equals_reference(dir, o, kView, 40);
  if (!r) return;
  expect_summaries_count_the_boxes_tested(*r, dir / "cluster" / "stats.csv");
  EXPECT_NE(r->node1_log.find("occlusion back end: cpu-pyramid (auto: software renderer "), std::string::npos)
      << r->node1_log;
  // "occlusion back end B: N boxes tested (M occluded), Q occlusion queries issued, K boxes in D batch draws"
  auto batch_draws = [](const std::string& log, const std::string& test) -> std::pair<unsigned long, unsigned long> {
    const size_t at = log.find("occlusion back end " + test + ": ");
    if (at == std::string::npos) return {~0ul, ~0ul};
    const size_t end = log.find('\n', at);
    const size_t in = log.find(" boxes in ", at), draws = log.find(" batch draws", at);
    if (in == std::string::npos || draws == std::string::npos || draws > end) return {0, 0};
    const size_t boxes = log.rfind(", ", in);
    return {std::stoul(log.substr(boxes + 2, in - boxes - 2)), std::stoul(log.substr(in + 10, draws - in - 10))};
  };
  const auto q = batch_draws(r->node0_log, "queries"), b = batch_draws(r->node1_log, "cpu-pyramid");
  EXPECT_EQ(q, std::make_pair(0ul, 0ul)) << r->node0_log;
  ASSERT_NE(b.first, ~0ul) << "node 1 (default) did not report back end cpu-pyramid:\n" << r->node1_log;
  EXPECT_GT(b.first, 0u) << r->node1_log;
  EXPECT_GT(b.second, 0u) << r->node1_log;
  // "..., N proven occluded by the depth pyramid"
  const size_t at = r->node1_log.find(" proven occluded by the depth pyramid");
  ASSERT_NE(at, std::string::npos) << r->node1_log;
  const size_t from = r->node1_log.rfind(", ", at);
  EXPECT_GT(std::stoul(r->node1_log.substr(from + 2, at - from - 2)), 0u) << r->node1_log;
}

// The CPU back end (common/cull/cpu_backend.hpp; auto on llvmpipe at tau 0): node 0 told to use
// cpu-pyramid (GL's depth), node 1 by default on the CPU, where boxes and the leaves whose boxes
// show by their own triangles are tested. The frames are the reference's, node 1 says so at
// start-up, tested boxes on the CPU and found leaves hidden by their triangles (pipes: long thin
// objects whose boxes show past what hides them), node 0 none of that. Adaptive queries and the
// visibility hold at auto: off on node 1 (the CPU back end), on node 0, which skips tests.
TEST(Cluster, PipesOrbitWithTheOrInGlOnNode0AndOnTheCpuOnNode1EqualsReference) {
  fs::path dir = fresh_dir("pipes_or_cpu");
  ClusterOptions o = cluster("pipes", "orbit:40");
  o.node0 = {"--backend", "cpu-pyramid"};
  const std::optional<ClusterRun> r = expect_cluster_equals_reference(dir, o, kView, 40);
  if (!r) return;
  expect_summaries_count_the_boxes_tested(*r, dir / "cluster" / "stats.csv");
  // "occlusion back end cpu: N boxes tested (...), ..., L leaves tested by their triangles (H hidden)"
  auto hidden = [](const std::string& log) {
    const size_t at = log.find(" leaves tested by their triangles (");
    return at == std::string::npos ? -1 : number_before(log, " hidden)", at);
  };
  EXPECT_NE(r->node0_log.find("occlusion back end: cpu-pyramid (--backend cpu-pyramid; adaptive queries on, "
                              "visibility hold 2)"),
            std::string::npos)
      << r->node0_log;
  EXPECT_EQ(hidden(r->node0_log), -1) << r->node0_log;
  EXPECT_NE(r->node1_log.find("occlusion back end: cpu (auto: software renderer "), std::string::npos) << r->node1_log;
  EXPECT_NE(r->node1_log.find(", tau 0; adaptive queries off, visibility hold 0)"), std::string::npos) << r->node1_log;
  EXPECT_GT(number_before(r->node1_log, " boxes tested ("), 0) << r->node1_log;
  EXPECT_GT(hidden(r->node1_log), 0) << r->node1_log;
  // "N nodes assumed visible by adaptive queries (...; M renderables kept by the visibility hold)"
  auto skipped = [](const std::string& log) { return number_before(log, " nodes assumed visible by adaptive queries"); };
  auto held = [](const std::string& log) { return number_before(log, " renderables kept by the visibility hold"); };
  EXPECT_EQ(skipped(r->node1_log), 0) << r->node1_log;
  EXPECT_EQ(held(r->node1_log), 0) << r->node1_log;
  EXPECT_GT(skipped(r->node0_log), 0) << r->node0_log;
}

// Defaults by renderer class: with every process told it runs on a hardware GPU
// (OCC_RENDERER_CLASS=hardware, on llvmpipe), --backend auto picks occlusion queries (no depth
// read-back on the frame's path) and two passes are off; the frames still equal the reference.
// The software choice (cpu-pyramid, two passes by measurement) is every other test's default.
TEST(Cluster, HardwareRendererDefaultsQueriesNoTwoPassEqualsReference) {
  fs::path dir = fresh_dir("hardware_defaults");
  ClusterOptions o = cluster("plant:0.3", "walk:30");
  ::setenv("OCC_RENDERER_CLASS", "hardware", 1);  // inherited by the processes this test starts
  const std::optional<ClusterRun> r = expect_cluster_equals_reference(dir, o, kView, 30);
  ::unsetenv("OCC_RENDERER_CLASS");
  if (!r) return;
  for (const std::string* log : {&r->node0_log, &r->node1_log}) {
    EXPECT_NE(log->find("hardware renderer (OCC_RENDERER_CLASS)"), std::string::npos) << *log;
    EXPECT_NE(log->find("occlusion back end: queries (auto: hardware renderer "), std::string::npos) << *log;
    EXPECT_NE(log->find("occlusion back end queries: "), std::string::npos) << *log;  // the summary: what it ran
    EXPECT_EQ(log->find("cpu-pyramid"), std::string::npos) << *log;
  }
  EXPECT_NE(r->rvg_log.find("two passes off (--occlusion auto on a hardware renderer"), std::string::npos)
      << r->rvg_log;
}

TEST(Cluster, DuplexWalkEqualsReference) {
  if (!have_shared()) GTEST_SKIP() << "../shared/scenes not found: the duplex test needs it";
  expect_cluster_equals_reference("duplex", shared("scenes/duplex/Duplex_A_20110505.gltf"), "walk:60", 60, false);
}

// What incremental transmission saves, computed in every run: each frame's full_set_bytes is
// what the whole visible set would have taken (its camera and end of frame as received, every id
// in chunks of the paper's b); on a walk the diffs take fewer bytes.
TEST(Cluster, IncrementalDiffsUseFewerBytesThanTheWholeSets) {
  fs::path dir = fresh_dir("fullsets");
  ClusterOptions o = cluster(kCity, "walk:90");
  o.client = {"--images", "off"};
  ClusterRun r = run_cluster(dir / "inc", o);
  ASSERT_EQ(r.rvg_code, 0) << r.rvg_log;
  auto a = read_csv(dir / "inc" / "stats.csv");
  ASSERT_EQ(a["visible"].size(), 90u);
  for (size_t f = 0; f < 90; ++f) {
    const double v = a["visible"][f], chunks = std::ceil(v / 100);
    EXPECT_GE(a["full_set_bytes"][f], 4 * v + 18 * chunks) << "frame " << f;
  }
  EXPECT_LT(sum(a["bytes_received"]), sum(a["full_set_bytes"]));
  EXPECT_NE(r.rvg_log.find("the whole visible sets would take"), std::string::npos) << r.rvg_log;
}

// --on-node-failure exit (benchmarks): a killed node ends the run at once, named. The default,
// degrade, goes on without it: integration_recovery_test.cpp.
TEST(ClusterFaults, KilledSwitchNodeIsReportedWithNodeAndFrameAndNoPartialImage) {
  ClusterOptions o = cluster(kCity, "walk:100000");
  o.client = {"--on-node-failure", "exit"};
  Cluster c(fresh_dir("kill") / "cluster", o);
  // Kill node 1 once frames are flowing.
  ASSERT_TRUE(c.start_and_show(20)) << c.logs();  // 3 process starts: slow under load
  c.node1().kill_now();
  expect_client_stops_naming_node1(c.client(), false);  // ended by the disconnect, not the 20 s timeout
  // Node 0 ends too, not hanging: with an error if it noticed node 1's death first, cleanly if
  // the render client's goodbye (which says it failed) came first.
  const int n0_code = c.node0().wait(30s);
  EXPECT_TRUE(n0_code == 0 || n0_code == 1) << c.node0().log();
  EXPECT_NE(c.node0().log().find(n0_code == 1 ? "switch node 1" : "render client failed"), std::string::npos)
      << c.node0().log();
  // Every frame file is complete and has its stats row: nothing partial was written.
  expect_no_partial_frames(c.out());
}

TEST(ClusterFaults, SceneFingerprintMismatchIsRefusedAtHandshakeNamingBoth) {
  ClusterOptions o("", "", kSmallView);  // the scene differs: each node names its own
  o.timeout_ms = kRefusalTimeoutMs;
  o.node0 = {"--scene", "city:4x4:2:5:1"};
  o.node1 = {"--scene", "city:5x4:2:5:1"};
  const auto r = expect_handshake_refused(fresh_dir("fingerprint"), o);
  ASSERT_TRUE(r);
  const std::string &l1 = r->node1_log, &l0 = r->node0_log;
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
  ClusterOptions o = cluster(kCity, "walk:40");
  o.all = {"--camera-mode", "latest"};
  // Without images (fast client) and with them (PNG writing makes the client the slowest stage:
  // before, both nodes then used one camera for two frames and a backlog of frames built up).
  for (bool images : {false, true}) {
    o.client = images ? std::vector<std::string>{"--lookahead", "3"} : std::vector<std::string>{"--images", "off"};
    const fs::path run = dir / (images ? "slow" : "fast");
    ClusterRun r = run_cluster(run, o);
    ASSERT_EQ(r.rvg_code, 0) << r.rvg_log;
    EXPECT_EQ(r.node0_code, 0) << r.node0_log;
    EXPECT_EQ(r.node1_code, 0) << r.node1_log;
    auto stats = read_csv(run / "stats.csv");
    ASSERT_FALSE(stats["camera"].empty());
    EXPECT_EQ(stats["camera"].back(), 39);
    // Each frame uses the newest camera after the previous frame's (never one camera twice), and
    // no more cameras than the lookahead are ever in flight. Every frame's set was verified (the
    // client exits non-zero otherwise).
    EXPECT_LE(stats["camera"].size(), 40u);
    const double lookahead = images ? 3 : 2;
    for (size_t i = 0; i < stats["camera"].size(); ++i) {
      if (i > 0) {
        EXPECT_GT(stats["camera"][i], stats["camera"][i - 1]) << "frame " << i;
      }
      EXPECT_LE(stats["camera_gap"][i], lookahead - 1) << "frame " << i;
    }
    // A stage's time lies within the run (the wait for the other node's camera once wrapped or_ms
    // round to a huge value in this mode).
    const double run_ms = sum(stats["frame_interval_ms"]);
    for (const char* stage : {"hc_ms", "or_ms"})
      for (double v : stats[stage]) EXPECT_LE(v, run_ms) << stage;
  }
}

// Levels of detail (tau > 0): every process verifies every frame (set hash and front hash), the
// LOD cache is built once and reused, fewer triangles are drawn than at tau = 0, and the image
// stays close to the full-detail reference.
TEST(ClusterLod, PixelErrorWalkVerifiesOnAllProcessesAndStaysCloseToReference) {
  fs::path dir = fresh_dir("lod");
  const std::string path = "walk:60";
  ClusterOptions o = cluster(kCity, path);
  o.all = {"--lod-cache", (dir / "cache").string()};
  o.client = {"--images", "off"};
  // GL's depth at both: at tau 0 the CPU back end (llvmpipe's default) also culls leaves by their
  // own triangles, which levels of detail do not (the test compares what LODs save).
  o.node0 = o.node1 = {"--backend", "cpu-pyramid"};
  ClusterRun exact = run_cluster(dir / "tau0", o);
  ASSERT_EQ(exact.rvg_code, 0) << exact.rvg_log;
  o.all.insert(o.all.end(), {"--pixel-error", "3"});
  o.client = {};
  ClusterRun r = run_cluster(dir / "tau3", o);
  ASSERT_EQ(r.rvg_code, 0) << r.logs();
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
  ASSERT_EQ(run_reference(dir / "reference", kCity, path, kView).code, 0);
  const Outcome diff = frame_diff(dir / "reference", dir / "tau3", {"--threshold", "16", "--max-fraction", "0.05", "--psnr"});
  EXPECT_EQ(diff.code, 0) << differing_frames(diff.log);
  EXPECT_NE(diff.log.find("psnr_db="), std::string::npos) << differing_frames(diff.log);
}

// The CPU back end at tau > 0 (--backend cpu: boxes tested against the CPU's depth, no leaf
// tests; coarser levels and HLODs are left out of that depth, which only proves less): every
// process verifies every frame, the image stays as close to full detail as the LOD bound allows,
// and the summaries count the boxes tested. With visible-pixel LOD the same flag is refused at
// start, in one line naming it.
TEST(ClusterLod, CpuBackendAtPixelErrorStaysCloseToReferenceAndRefusesVisiblePixelLod) {
  fs::path dir = fresh_dir("lod_cpu");
  const std::string path = "walk:40";
  ClusterOptions o = cluster(kCity, path);
  o.all = {"--lod-cache", (dir / "cache").string(), "--pixel-error", "3"};
  o.node0 = o.node1 = {"--backend", "cpu"};
  ClusterRun r = run_cluster(dir / "tau3", o);
  ASSERT_EQ(r.rvg_code, 0) << r.logs();
  EXPECT_EQ(r.node0_code, 0) << r.node0_log;
  EXPECT_EQ(r.node1_code, 0) << r.node1_log;
  for (const std::string* log : {&r.node0_log, &r.node1_log})
    EXPECT_NE(log->find("occlusion back end: cpu (--backend cpu; "), std::string::npos) << *log;
  expect_summaries_count_the_boxes_tested(r, dir / "tau3" / "stats.csv");
  ASSERT_EQ(run_reference(dir / "reference", kCity, path, kView).code, 0);
  const Outcome diff = frame_diff(dir / "reference", dir / "tau3", {"--threshold", "16", "--max-fraction", "0.05"});
  EXPECT_EQ(diff.code, 0) << differing_frames(diff.log);

  const Outcome refused = run_to_end({bin("switch_node"), "--id", "0", "--scene", kCity, "--pixel-error", "3",
                                      "--visible-pixel-lod", "on", "--backend", "cpu", "--width", "64", "--height", "64",
                                      "--lod-cache", (dir / "cache").string()},
                                     dir / "refused.log", 120s);
  expect_one_error(refused, {"--backend cpu: --visible-pixel-lod needs sample counts"}, {.code = 2});
}

TEST(ClusterLod, VisiblePixelLodAndNoFrontTrackingRunVerified) {
  fs::path dir = fresh_dir("lodvp");
  const std::vector<std::string> cache = {"--lod-cache", (dir / "cache").string()};
  for (auto extra : std::vector<std::vector<std::string>>{{"--pixel-error", "5", "--visible-pixel-lod", "on"},
                                                          {"--pixel-error", "5", "--front-tracking", "off"}}) {
    extra.insert(extra.end(), cache.begin(), cache.end());
    const fs::path out = dir / extra[3];
    ClusterOptions o = cluster(kCity, "walk:40");
    o.all = extra;
    o.client = {"--images", "off"};
    ClusterRun r = run_cluster(out, o);
    ASSERT_EQ(r.rvg_code, 0) << r.logs();
    EXPECT_EQ(r.node0_code, 0) << r.node0_log;
    EXPECT_EQ(r.node1_code, 0) << r.node1_log;
    EXPECT_EQ(read_csv(out / "stats.csv")["frame"].size(), 40u);
  }
}

TEST(ClusterLod, MismatchedPixelErrorIsRefusedAtHandshake) {
  fs::path out = fresh_dir("lodmismatch");
  ClusterOptions o("city:4x4:2:5:1", "", kSmallView);
  o.timeout_ms = kRefusalTimeoutMs;
  o.all = {"--lod-cache", (out / "cache").string()};
  o.node0 = {"--pixel-error", "1"};
  o.node1 = {"--pixel-error", "2"};
  const auto r = expect_handshake_refused(out, o);
  ASSERT_TRUE(r);
  EXPECT_NE(r->node1_log.find("config hash"), std::string::npos) << r->node1_log;
}

namespace {

// A process's "geometry:" line (GeometryPool, print_geometry_line): field `name`, or -1.
double geometry_field(const std::string& log, const std::string& name) {
  const size_t line = log.find(": geometry: budget_mb=");
  if (line == std::string::npos) return -1;
  const size_t at = log.find(" " + name + "=", line);
  if (at == std::string::npos || at > log.find('\n', line)) return -1;
  return std::stod(log.substr(at + name.size() + 2));
}

}  // namespace

// Every process keeps its geometry within a budget far below the plant's (2 MB against
// its 10 MB of meshes at tau 0, 1 MB against 18 MB of meshes and LODs at tau 2), read lazily from its scene and LOD caches (built here by node 0,
// the LODs from the scene cache read whole, then read back lazily). Pieces are evicted and read
// again and draw calls cut into windows; the frames wait for what they need, so at tau 0 they are
// the reference's, and at tau 2 those of the same cluster with everything resident.
TEST(ClusterBudget, PlantFarBelowItsSizeEqualsReferenceAndTheResidentCluster) {
  fs::path dir = fresh_dir("budget");
  const std::vector<std::string> cache = {"--lod-cache", (dir / "cache").string()};
  ClusterOptions o = cluster("plant:0.3", "walk:40");
  o.all = {"--geometry-budget", "2"};
  o.all.insert(o.all.end(), cache.begin(), cache.end());
  const std::optional<ClusterRun> r = expect_cluster_equals_reference(dir / "tau0", o, kView, 40);
  if (!r) return;
  for (const std::string* log : {&r->rvg_log, &r->node0_log, &r->node1_log}) {
    EXPECT_NE(log->find("geometry streams:"), std::string::npos) << *log;
    EXPECT_EQ(geometry_field(*log, "budget_mb"), 2.0) << *log;
    EXPECT_GT(geometry_field(*log, "evictions"), 0.0) << *log;
    EXPECT_GT(geometry_field(*log, "uploads"), geometry_field(*log, "pieces")) << *log;  // read again
  }
  auto stats = read_csv(dir / "tau0" / "cluster" / "stats.csv");
  EXPECT_GT(sum(stats["geometry_waits"]), 0.0);

  o.all[1] = "1";  // tau 2 draws coarse LODs: 1.7 MB of pieces over the walk, so a smaller budget
  o.all.insert(o.all.end(), {"--pixel-error", "2"});
  const ClusterRun streamed = run_cluster(dir / "tau2_budget", o);
  ASSERT_EQ(streamed.rvg_code, 0) << streamed.logs();
  EXPECT_NE(streamed.node0_log.find("built LODs"), std::string::npos) << streamed.node0_log;
  EXPECT_NE(streamed.rvg_log.find("stay in the mapped file"), std::string::npos) << streamed.rvg_log;
  EXPECT_GT(geometry_field(streamed.rvg_log, "evictions"), 0.0) << streamed.rvg_log;
  o.all[1] = "all";
  const ClusterRun resident = run_cluster(dir / "tau2_all", o);
  ASSERT_EQ(resident.rvg_code, 0) << resident.logs();
  EXPECT_EQ(resident.rvg_log.find("geometry streams:"), std::string::npos) << resident.rvg_log;
  const Outcome diff = frame_diff(dir / "tau2_all", dir / "tau2_budget");
  EXPECT_EQ(diff.code, 0) << differing_frames(diff.log);
  EXPECT_NE(diff_summary(diff.log).find("differing_pixels=0"), std::string::npos) << differing_frames(diff.log);
}

namespace {

// The render client's run table (render_client/run_table.hpp): its lines from the "run (" title
// up to the summary: line, as label -> the text after the label.
std::map<std::string, std::string> run_table(const std::string& log, std::string* title) {
  std::map<std::string, std::string> rows;
  const size_t begin = log.find("\nrun (");
  const size_t end = log.find("\nsummary: ", begin);
  if (begin == std::string::npos || end == std::string::npos) return rows;
  std::istringstream lines(log.substr(begin + 1, end - begin - 1));
  std::string line;
  std::getline(lines, line);
  *title = line;
  while (std::getline(lines, line)) {
    if (line.rfind("  ", 0) != 0) continue;
    const size_t gap = line.find("  ", 2);  // the label column ends at the first double space
    if (gap == std::string::npos) continue;
    const size_t value = line.find_first_not_of(' ', gap);
    rows[line.substr(2, gap - 2)] = value == std::string::npos ? "" : line.substr(value);
  }
  return rows;
}

// The sorted values' element at n / 2 and at min(n - 1, n * 99 / 100), as the table takes them.
std::pair<double, double> median_p99(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return {v[v.size() / 2], v[std::min(v.size() - 1, v.size() * 99 / 100)]};
}

double summary_value(const std::string& log, const std::string& key) {
  const size_t at = log.find(" " + key + "=", log.find("summary: "));
  return at == std::string::npos ? -1 : std::stod(log.substr(at + key.size() + 2));
}

}  // namespace

// The table a person reads at the end of a run says what the run's stats.csv and logs say: its
// medians are those of the stats.csv columns (the frame interval, the render client's draw, each
// node's OR and HC over the frames it served), its bytes and culled share the summary line's, and
// its back ends are those each node named at start-up (node 0 with the OR in GL tests with the
// cpu-pyramid, node 1 on the CPU).
TEST(Cluster, RunTableAgreesWithStatsCsvAndTheNodesStartUp) {
  fs::path dir = fresh_dir("run_table");
  ClusterOptions o = cluster(kCity, "orbit:16");
  o.node0 = {"--backend", "cpu-pyramid"};
  const ClusterRun r = run_cluster(dir, o);
  ASSERT_EQ(r.rvg_code, 0) << r.logs();
  ASSERT_EQ(r.node0_code, 0) << r.logs();
  ASSERT_EQ(r.node1_code, 0) << r.logs();
  std::string title;
  const std::map<std::string, std::string> rows = run_table(r.rvg_log, &title);
  EXPECT_EQ(title, "run (16 frames)") << r.rvg_log;
  for (const char* label : {"frame ms", "render client draw ms", "render client wait ms", "node 0 OR ms", "node 0 HC ms",
                            "node 1 OR ms", "node 1 HC ms", "fps", "culled (not drawn)", "wrong pixels", "bytes a frame",
                            "occlusion back end"})
    EXPECT_EQ(rows.count(label), 1u) << label << " missing:\n" << r.rvg_log;
  if (rows.size() < 12) return;

  auto stats = read_csv(dir / "stats.csv");
  ASSERT_EQ(stats["frame"].size(), 16u);
  // A time row: "median p99", each within the rounding of the table (2 decimals) and the CSV.
  auto expect_times = [&](const std::string& label, const std::vector<double>& values) {
    std::istringstream cells(rows.at(label));
    double median = -1, p99 = -1;
    cells >> median >> p99;
    const auto [m, p] = median_p99(values);
    EXPECT_NEAR(median, m, 0.006) << label << ": " << rows.at(label);
    EXPECT_NEAR(p99, p, 0.006) << label << ": " << rows.at(label);
  };
  expect_times("frame ms", stats["frame_interval_ms"]);
  expect_times("render client draw ms", stats["rvg_ms"]);
  expect_times("render client wait ms", stats["wait_ms"]);
  for (int k = 0; k < 2; ++k) {
    std::vector<double> or_ms, hc_ms;
    for (size_t f = 0; f < stats["frame"].size(); ++f)
      if (stats["hc_node"][f] == k) {
        or_ms.push_back(stats["or_ms"][f]);
        hc_ms.push_back(stats["hc_ms"][f]);
      }
    ASSERT_EQ(or_ms.size(), 8u) << "node " << k;  // the switch: every other frame
    expect_times("node " + std::to_string(k) + " OR ms", or_ms);
    expect_times("node " + std::to_string(k) + " HC ms", hc_ms);
  }
  EXPECT_NEAR(summary_value(r.rvg_log, "frame_ms_median"), median_p99(stats["frame_interval_ms"]).first, 0.006);
  char bytes[128];
  std::snprintf(bytes, sizeof bytes, "%.0f B received from the nodes (mean; the whole visible sets would take %.0f B)",
                sum(stats["bytes_received"]) / 16, sum(stats["full_set_bytes"]) / 16);
  EXPECT_EQ(rows.at("bytes a frame"), bytes);
  char culled[64];
  std::snprintf(culled, sizeof culled, "%.1f %% of objects, %.1f %% of triangles", summary_value(r.rvg_log, "culled_pct"),
                summary_value(r.rvg_log, "triangles_culled_pct"));
  EXPECT_EQ(rows.at("culled (not drawn)"), culled);
  EXPECT_EQ(rows.at("wrong pixels").rfind("not checked", 0), 0u) << rows.at("wrong pixels");  // the client compares sets
  // "switch_node K: occlusion back end: NAME (why ...)", once, at start-up.
  std::string names;
  for (const auto& [k, log] : {std::pair{0, &r.node0_log}, std::pair{1, &r.node1_log}}) {
    const std::string line = "switch_node " + std::to_string(k) + ": occlusion back end: ";
    const size_t at = log->find(line);
    ASSERT_NE(at, std::string::npos) << *log;
    EXPECT_EQ(log->find(line, at + 1), std::string::npos) << *log;
    const std::string name = log->substr(at + line.size(), log->find(' ', at + line.size()) - at - line.size());
    names += (k ? ", node 1 " : "node 0 ") + name;
  }
  EXPECT_EQ(names, "node 0 cpu-pyramid, node 1 cpu");
  EXPECT_EQ(rows.at("occlusion back end"), names);
}

// The reference's table (one process) says what its stats.csv says: the draw's median and p99,
// the share of objects it did not draw, --exact's missed objects, and its back end (CHC: queries).
TEST(Cluster, ReferenceRunTableAgreesWithItsStatsCsv) {
  fs::path dir = fresh_dir("reference_table");
  const Outcome ref = run_reference(dir, kCity, "orbit:8", {"--width", "64", "--height", "64", "--cull", "chc", "--exact"});
  ASSERT_EQ(ref.code, 0) << ref.log;
  std::string title;
  // The reference's key=value line starts "reference (chc): "; the table ends before it.
  const std::string log = std::regex_replace(ref.log, std::regex("\nreference \\(chc\\): "), "\nsummary: ");
  const std::map<std::string, std::string> rows = run_table(log, &title);
  EXPECT_EQ(title, "run (8 frames, one process: --cull chc)") << ref.log;
  auto stats = read_csv(dir / "stats.csv");
  ASSERT_EQ(stats["frame"].size(), 8u);
  ASSERT_EQ(rows.count("frame ms (draw)"), 1u) << ref.log;
  std::istringstream cells(rows.at("frame ms (draw)"));
  double median = -1, p99 = -1;
  cells >> median >> p99;
  EXPECT_NEAR(median, median_p99(stats["render_ms"]).first, 0.006) << ref.log;
  EXPECT_NEAR(p99, median_p99(stats["render_ms"]).second, 0.006) << ref.log;
  EXPECT_EQ(rows.at("wrong pixels"),
            "not checked (frame_diff compares frames with a --cull frustum run's); --exact: " +
                std::to_string(long(sum(stats["missed_visible"]))) + " visible objects not drawn");
  EXPECT_EQ(sum(stats["missed_visible"]), 0.0);  // CHC is conservative
  EXPECT_EQ(rows.at("occlusion back end"), "queries (GL occlusion queries)");
  EXPECT_EQ(rows.count("culled (not drawn)"), 1u) << ref.log;
  EXPECT_EQ(rows.count("bytes a frame"), 0u) << ref.log;  // one process
}
