// scripts/cluster.sh --hosts: the three processes on three hosts over ssh. The hosts are
// three network namespaces made by tests/ssh_netns.sh, each with its own address and its own sshd
// (generated host and user keys) bound to that address only. Frames equal the reference; the
// launcher leaves no process and no work folder behind on any host, also when one fails; an
// unreachable host or a wrong scene path is named with its reason. Root, ip netns and sshd
// (Debian openssh-server, scripts/setup.sh) needed: skipped with a message otherwise.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>

#include "integration_util.hpp"

using namespace occtest;
using namespace std::chrono_literals;

namespace {

const std::string kScene = "city:3x3:2:5:1";
const std::vector<std::string> kView = {"--width", "96", "--height", "72"};

std::string helper() { return std::string(OCC_SOURCE_DIR) + "/tests/ssh_netns.sh"; }

// The three hosts for one test: up in SetUp, down (sshds stopped, namespaces removed) in TearDown.
class Hosts : public testing::Test {
 protected:
  void SetUp() override {
    if (::geteuid() != 0) GTEST_SKIP() << "needs root for network namespaces";
    if (std::system("ip netns list >/dev/null 2>&1") != 0) GTEST_SKIP() << "ip netns unavailable";
    if (!fs::exists("/usr/sbin/sshd")) GTEST_SKIP() << "needs sshd (Debian openssh-server, scripts/setup.sh)";
    dir_ = fresh_dir("hosts_" + std::string(testing::UnitTest::GetInstance()->current_test_info()->name()));
    const Outcome up = run_to_end({helper(), "up", (dir_ / "ssh").string()}, dir_ / "up.log", 120s);
    ASSERT_EQ(up.code, 0) << up.log;
    hosts_ = up.log.substr(0, up.log.find('\n'));
    std::stringstream names(read_file(dir_ / "ssh" / "names"));
    names >> tag_;
    ::setenv("OCC_BIN", OCC_BIN_DIR, 1);
  }
  void TearDown() override {
    if (!dir_.empty()) run_to_end({helper(), "down", (dir_ / "ssh").string()}, dir_ / "down.log", 60s);
  }
  std::vector<std::string> cluster_args(const std::string& hosts, const std::string& scene, const std::string& path) {
    std::vector<std::string> a = {"/bin/bash", std::string(OCC_SOURCE_DIR) + "/scripts/cluster.sh", "--hosts", hosts,
                                  "--ssh-config", (dir_ / "ssh" / "ssh_config").string(), "--remote-out",
                                  (dir_ / "remote").string(), "--scene", scene, "--path", path, "--out",
                                  (dir_ / "cluster").string()};
    a.insert(a.end(), kView.begin(), kView.end());
    return a;
  }
  Outcome cluster(const std::string& hosts, const std::string& scene, const std::string& path) {
    return run_to_end(cluster_args(hosts, scene, path), dir_ / "cluster.log", 240s);
  }
  // Nothing but its sshd runs in namespace i (within 10 s: what was stopped may still be exiting),
  // and the work folder is gone.
  void expect_nothing_left() {
    for (int i = 0; i < 3; ++i) {
      int left = 0;
      for (int t = 0; t < 100 && left != 1; ++t) {
        if (t) std::this_thread::sleep_for(100ms);
        const Outcome pids = run_to_end({"/bin/sh", "-c", "ip netns pids " + tag_ + std::to_string(i) + " | wc -l"},
                                        dir_ / "pids.log", 30s);
        left = std::stoi(pids.log);
      }
      EXPECT_EQ(left, 1) << "namespace " << i << " still runs processes besides sshd";
    }
    EXPECT_FALSE(fs::exists(dir_ / "remote"));
  }
  fs::path dir_;
  std::string hosts_, tag_;
};

}  // namespace

TEST_F(Hosts, ClusterOverSshFramesEqualTheReferenceAndNothingIsLeft) {
  const Outcome r = cluster(hosts_, kScene, "walk:40");
  ASSERT_EQ(r.code, 0) << r.log;
  EXPECT_NE(r.log.find("summary: frames=40 "), std::string::npos) << r.log;
  const std::string h0 = hosts_.substr(0, hosts_.find(','));
  EXPECT_NE(r.log.find("cluster_rank 0 (node0 on " + h0 + "): listening at " + h0 + ":"), std::string::npos) << r.log;
  // The logs of all three came back, and the client reached node 0 at its namespace's address.
  for (const char* log : {"node0.log", "node1.log", "render_client.log"})
    EXPECT_TRUE(fs::exists(dir_ / "cluster" / log)) << log;
  EXPECT_NE(read_file(dir_ / "cluster" / "render_client.log").find("connected to switch node 0 (" + h0 + ":"),
            std::string::npos);
  expect_nothing_left();
  const Outcome ref = run_reference(dir_ / "reference", kScene, "walk:40", kView);
  ASSERT_EQ(ref.code, 0) << ref.log;
  const Outcome diff = frame_diff(dir_ / "reference", dir_ / "cluster");
  ASSERT_NE(diff_summary(diff.log).find("frames=40"), std::string::npos) << differing_frames(diff.log);
  EXPECT_NE(diff_summary(diff.log).find(" differing_pixels=0 "), std::string::npos) << differing_frames(diff.log);
}

TEST_F(Hosts, AWrongScenePathOrAnUnreachableHostIsNamedAndNothingIsLeft) {
  const std::string missing = (dir_ / "no_such_scene.gltf").string();
  const Outcome bad = cluster(hosts_, missing, "walk:10");
  EXPECT_EQ(bad.code, 1) << bad.log;
  EXPECT_NE(bad.log.find("node0 on " + hosts_.substr(0, hosts_.find(',')) + " exited before listening"),
            std::string::npos)
      << bad.log;
  EXPECT_NE(bad.log.find("  error: " + missing + ": cannot open file"), std::string::npos) << bad.log;
  expect_nothing_left();
  // Node 1's host does not exist (an address of the bridge's subnet that nobody has).
  const std::string h0 = hosts_.substr(0, hosts_.find(','));
  const std::string nobody = h0.substr(0, h0.rfind('.') + 1) + std::to_string(std::stoi(h0.substr(h0.rfind('.') + 1)) + 20);
  const std::string hosts = h0 + "," + nobody + "," + hosts_.substr(hosts_.rfind(',') + 1);
  ::setenv("OCC_SSH_CONNECT_TIMEOUT_S", "2", 1);  // ssh's wait for the host that is not there
  const Outcome gone = cluster(hosts, kScene, "walk:10");
  ::unsetenv("OCC_SSH_CONNECT_TIMEOUT_S");
  EXPECT_EQ(gone.code, 1) << gone.log;
  EXPECT_NE(gone.log.find("error: host " + nobody + " (node1): unreachable over ssh"), std::string::npos) << gone.log;
  expect_nothing_left();
}

// Ctrl-C (SIGTERM here) mid-run: every process on every host is stopped, the work folders removed.
TEST_F(Hosts, InterruptedRunLeavesNothingBehind) {
  std::vector<std::string> a = cluster_args(hosts_, kScene, "walk:1000000");
  a.insert(a.end(), {"--images", "off"});
  Proc run(a, dir_ / "cluster.log");
  ASSERT_GE(wait_frames(dir_ / "remote" / "out" / "stats.csv", 5, 120s, &run), 5u) << run.log();
  run.signal(SIGTERM);
  EXPECT_EQ(run.wait(120s), 130) << run.log();
  EXPECT_NE(run.log().find("cluster: interrupted, stopping all processes"), std::string::npos) << run.log();
  expect_nothing_left();
}
