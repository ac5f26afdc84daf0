// switch_node --serve through the real processes on loopback: each render client is a session of
// its own, and what a node reports at a session's end counts that client's frames only (issue
// 32: the per-client state is made fresh for every client, not reset field by field).
#include <gtest/gtest.h>

#include <regex>

#include "cluster_run.hpp"

using namespace occtest;
using namespace std::chrono_literals;

namespace {

const std::vector<std::string> kView = {"--width", "160", "--height", "120"};

// A node's session summaries in its log, in order: its HC frames, and how many of them were sent
// as frustum sets (frames without occlusion).
struct SessionCounts {
  unsigned long hc_frames = 0, without_occlusion = 0;
};
std::vector<SessionCounts> session_counts(const std::string& log) {
  static const std::regex line(R"(switch_node \d: (\d+) HC frames, [^\n]*?; (\d+) frames without occlusion)");
  std::vector<SessionCounts> out;
  for (auto it = std::sregex_iterator(log.begin(), log.end(), line); it != std::sregex_iterator(); ++it)
    out.push_back({std::stoul((*it)[1]), std::stoul((*it)[2])});
  return out;
}

}  // namespace

// Two clients one after the other, every frame without occlusion (--occlusion-gate off): the
// second session's summary on each node counts the second client's frames, not both clients'.
TEST(Serve, EachSessionSummaryCountsOnlyItsOwnClientsFrames) {
  const fs::path dir = fresh_dir("serve_counts");
  ClusterOptions o("city:6x6:3:10:1", "walk:20", kView);
  o.node0 = o.node1 = {"--serve", "--sessions", "2"};
  o.occlusion_gate = "off";
  o.client = {"--no-images"};
  Cluster c(dir, o);
  ASSERT_TRUE(c.start()) << c.logs();
  ASSERT_EQ(c.client().wait(120s), 0) << c.logs();
  for (Proc* n : {&c.node0(), &c.node1()}) ASSERT_TRUE(wait_log(*n, "render client 1 done; waiting")) << c.logs();
  c.start_client();  // the second client: the same flags
  const ClusterRun r = c.finish();
  ASSERT_EQ(r.rvg_code, 0) << r.logs();
  ASSERT_EQ(r.node0_code, 0) << r.logs();
  ASSERT_EQ(r.node1_code, 0) << r.logs();
  ASSERT_EQ(read_csv(dir / "stats.csv")["frame"].size(), 20u);  // the second client's stats
  const std::vector<SessionCounts> n0 = session_counts(r.node0_log), n1 = session_counts(r.node1_log);
  ASSERT_EQ(n0.size(), 2u) << r.node0_log;
  ASSERT_EQ(n1.size(), 2u) << r.node1_log;
  for (size_t s = 0; s < 2; ++s) {
    EXPECT_EQ(n0[s].hc_frames + n1[s].hc_frames, 20u) << "session " << s + 1 << "\n" << r.logs();
    EXPECT_EQ(n0[s].without_occlusion, n0[s].hc_frames) << "session " << s + 1 << "\n" << r.node0_log;
    EXPECT_EQ(n1[s].without_occlusion, n1[s].hc_frames) << "session " << s + 1 << "\n" << r.node1_log;
  }
}
