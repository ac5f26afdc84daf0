// scripts/cluster.sh --netns: the three processes in three network namespaces joined by veth
// pairs (root only). Whatever happens, every namespace (and with it every veth and qdisc) it made
// is gone afterwards.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <set>

#include "integration_util.hpp"

using namespace occtest;
using namespace std::chrono_literals;

namespace {
std::set<std::string> namespaces() {
  std::set<std::string> out;
  FILE* f = ::popen("ip netns list 2>/dev/null", "r");
  if (!f) return out;
  char line[512];
  while (std::fgets(line, sizeof line, f)) {
    std::string s(line);
    out.insert(s.substr(0, s.find_first_of(" \n")));
  }
  ::pclose(f);
  return out;
}

std::vector<std::string> cluster_args(const fs::path& out, const std::string& frames) {
  return {"/bin/bash", std::string(OCC_SOURCE_DIR) + "/scripts/cluster.sh", "--netns", "--scene", "city:4x4:2:5:1",
          "--path", "walk", "--frames", frames, "--width", "96", "--height", "64", "--images", "off", "--link", "1:50",
          "--out", out.string()};
}

// Every test needs root and ip netns; the namespaces that exist before it must be all that exist
// after it.
class NetNs : public testing::Test {
 protected:
  void SetUp() override {
    if (::geteuid() != 0) GTEST_SKIP() << "needs root for network namespaces";
    if (std::system("ip netns list >/dev/null 2>&1") != 0) GTEST_SKIP() << "ip netns unavailable";
    before_ = namespaces();
  }
  std::set<std::string> before_;
};
}  // namespace

TEST_F(NetNs, ClusterRunsAcrossNamespacesAndLeavesNothingBehind) {
  fs::path out = fresh_dir("netns");
  Proc run(cluster_args(out, "16"), out / "cluster.log");
  ASSERT_EQ(run.wait(240s), 0) << run.log();
  EXPECT_NE(run.log().find("summary: frames=16"), std::string::npos) << run.log();
  EXPECT_NE(read_file(out / "node0.log").find("listening on 0.0.0.0"), std::string::npos);
  EXPECT_EQ(namespaces(), before_);
}

TEST_F(NetNs, InterruptedClusterStillRemovesItsNamespaces) {
  fs::path out = fresh_dir("netns_int");
  Proc run(cluster_args(out, "100000"), out / "cluster.log");
  ASSERT_GE(wait_frames(out / "stats.csv", 5, 30s), 5u) << run.log();
  EXPECT_GT(namespaces().size(), before_.size());  // they exist while it runs
  run.signal(SIGINT);
  EXPECT_EQ(run.wait(60s), 130) << run.log();
  EXPECT_EQ(namespaces(), before_);
}
