// Faults on the links, through the user-space link emulator: a slow, jittery link never changes a
// frame; a link that stalls or is cut makes the render client stop with an error that names the
// node and the frame, within its timeout, and nothing partial is written.
#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>

#include "integration_util.hpp"

using namespace occtest;
using namespace std::chrono_literals;

namespace {

const std::string kScene = "city:6x6:3:10:1";
const std::vector<std::string> kView = {"--width", "160", "--height", "120"};

// One command on link_relay's control port; returns the answer line.
std::string control(int port, const std::string& command) {
  int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(uint16_t(port));
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  std::string reply;
  if (::connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) == 0) {
    std::string line = command + "\n";
    (void)!::write(fd, line.data(), line.size());
    char c;
    while (::read(fd, &c, 1) == 1 && c != '\n') reply += c;
  }
  ::close(fd);
  return reply;
}

std::vector<std::string> with(std::vector<std::string> a, const std::vector<std::string>& more) {
  a.insert(a.end(), more.begin(), more.end());
  return a;
}

// Node 0 and node 1 direct, the render client reaching node 1 through a relay with a control port.
void stop_link_mid_run(const std::string& name, const std::string& command) {
  fs::path out = fresh_dir(name);
  std::vector<std::string> common = with({"--scene", kScene, "--timeout-ms", "3000"}, kView);
  Proc n0(with({bin("switch_node"), "--id", "0", "--port-file", (out / "n0.port").string()}, common), out / "node0.log");
  int p0 = wait_port(out / "n0.port", n0);
  Proc n1(with({bin("switch_node"), "--id", "1", "--peer", "127.0.0.1:" + std::to_string(p0), "--port-file",
                (out / "n1.port").string()}, common),
          out / "node1.log");
  int p1 = wait_port(out / "n1.port", n1);
  ASSERT_TRUE(p0 && p1);
  Proc relay({bin("link_relay"), "--target", "127.0.0.1:" + std::to_string(p1), "--port-file",
              (out / "relay.port").string(), "--control-port-file", (out / "control.port").string()},
             out / "relay.log");
  int pr = wait_port(out / "relay.port", relay), pc = wait_port(out / "control.port", relay);
  ASSERT_TRUE(pr && pc) << relay.log();
  Proc rvg(with({bin("render_client"), "--path", "walk:100000", "--out", out.string(),
                 "--connect", "127.0.0.1:" + std::to_string(p0), "--connect", "127.0.0.1:" + std::to_string(pr)},
                common),
           out / "render_client.log");
  for (int i = 0; i < 500 && read_csv(out / "stats.csv")["frame"].size() < 10; ++i) std::this_thread::sleep_for(20ms);
  ASSERT_GE(read_csv(out / "stats.csv")["frame"].size(), 10u) << rvg.log();
  EXPECT_EQ(control(pc, command).rfind("ok", 0), 0u);
  const auto t0 = std::chrono::steady_clock::now();
  EXPECT_EQ(rvg.wait(30s), 1) << rvg.log();
  const double waited_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  EXPECT_LT(waited_s, 15.0);  // the 3 s receive timeout (or the cut) ended it, not the test
  const std::string log = rvg.log();
  EXPECT_NE(log.find("error: render_client: frame "), std::string::npos) << log;
  EXPECT_NE(log.find("switch node 1"), std::string::npos) << log;
  // A clean goodbye is never the cause of an error: node 0 ends with node 1's failure, not "done".
  EXPECT_EQ(log.find("said bye: done"), std::string::npos) << log;
  size_t pngs = 0;
  for (auto& e : fs::directory_iterator(out)) {
    EXPECT_EQ(e.path().filename().string().find(".tmp"), std::string::npos);
    pngs += e.path().filename().string().rfind("frame_", 0) == 0;
  }
  EXPECT_EQ(pngs, read_csv(out / "stats.csv")["frame"].size());
  n0.wait(30s);
  n1.wait(30s);
}

}  // namespace

TEST(LinkFaults, SlowJitteryLinksNeverChangeAFrame) {
  fs::path out = fresh_dir("slowlink");
  Proc cluster({"/bin/bash", std::string(OCC_SOURCE_DIR) + "/scripts/cluster.sh", "--scene", kScene, "--path", "walk",
                "--frames", "30", "--width", "160", "--height", "120", "--link", "3:20:2", "--out",
                (out / "cluster").string()},
               out / "cluster.log");
  ASSERT_EQ(cluster.wait(240s), 0) << cluster.log();
  Proc ref(with({bin("render_client"), "--reference", "--scene", kScene, "--path", "walk:30", "--out",
                 (out / "ref").string()}, kView),
           out / "ref.log");
  ASSERT_EQ(ref.wait(120s), 0) << ref.log();
  Proc diff({bin("frame_diff"), (out / "ref").string(), (out / "cluster").string(), "--max-fraction", "0.0001"},
            out / "diff.log");
  EXPECT_EQ(diff.wait(60s), 0) << diff.log();
  // The relays really were in the path: each logged its connection with bytes both ways.
  EXPECT_NE(read_file(out / "cluster" / "relay_rvg1.log").find("closed"), std::string::npos);
}

TEST(LinkFaults, StalledLinkEndsTheClientWithANamedErrorWithinItsTimeout) {
  stop_link_mid_run("stall", "stall");
}

TEST(LinkFaults, CutLinkEndsTheClientWithANamedError) { stop_link_mid_run("cut", "cut"); }
