// Faults on the links, through the user-space link emulator: a slow, jittery link never changes a
// frame; with --on-node-failure exit, a link that stalls or is cut makes the render client stop
// with an error that names the node and the frame, within its timeout, and nothing partial is
// written (what the default, degrade, does: integration_recovery_test.cpp).
#include <gtest/gtest.h>

#include "cluster_run.hpp"

using namespace occtest;
using namespace std::chrono_literals;

namespace {

const std::string kScene = "city:6x6:3:10:1";
const std::vector<std::string> kView = {"--width", "160", "--height", "120"};

// Node 0 and node 1 direct, the render client reaching node 1 through a relay with a control port;
// `command` on the control port once frames flow.
void stop_link_mid_run(const std::string& name, const std::string& command) {
  ClusterOptions o(kScene, "walk:100000", kView);
  o.relay_node1 = true;
  // The default, degrade: integration_recovery_test.cpp. The short receive timeout is the
  // client's only: the nodes' --timeout-ms also bounds their wait for the processes started after
  // them, which takes seconds on a loaded machine (a node timeout that short can leave node 0
  // without a peer).
  o.client = {"--on-node-failure", "exit", "--timeout-ms", "3000"};
  Cluster c(fresh_dir(name), o);
  ASSERT_TRUE(c.start_and_show(10)) << c.logs();
  EXPECT_EQ(c.control(command).rfind("ok", 0), 0u);
  // The 3 s receive timeout (the stall) or the disconnect (the cut) ended it, as its error says.
  const std::string log = expect_client_stops_naming_node1(c.client(), command == "stall");
  // A clean goodbye is never the cause of an error: node 0 ends with node 1's failure, not "done".
  EXPECT_EQ(log.find("said bye: done"), std::string::npos) << log;
  expect_no_partial_frames(c.out());
  // Node 1 may still wait behind the stalled relay for the client: the cut ends that wait.
  if (command != "cut") c.control("cut");
  c.finish();
}

}  // namespace

TEST(LinkFaults, SlowJitteryLinksNeverChangeAFrame) {
  fs::path out = fresh_dir("slowlink");
  Proc cluster({"/bin/bash", std::string(OCC_SOURCE_DIR) + "/scripts/cluster.sh", "--scene", kScene, "--path", "walk",
                "--frames", "30", "--width", "160", "--height", "120", "--link", "3:20:2", "--out",
                (out / "cluster").string()},
               out / "cluster.log");
  ASSERT_EQ(cluster.wait(240s), 0) << cluster.log();
  const Outcome ref = run_reference(out / "ref", kScene, "walk:30", kView, 120s);
  ASSERT_EQ(ref.code, 0) << ref.log;
  const Outcome diff = frame_diff(out / "ref", out / "cluster");
  EXPECT_EQ(diff.code, 0) << differing_frames(diff.log);
  // The relays really were in the path: each logged its connection with bytes both ways.
  EXPECT_NE(read_file(out / "cluster" / "relay_rvg1.log").find("closed"), std::string::npos);
}

TEST(LinkFaults, StalledLinkEndsTheClientWithANamedErrorWithinItsTimeout) {
  stop_link_mid_run("stall", "stall");
}

TEST(LinkFaults, CutLinkEndsTheClientWithANamedError) { stop_link_mid_run("cut", "cut"); }
