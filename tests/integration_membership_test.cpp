// Cluster membership through the real processes on loopback: a cluster key keeps processes
// without it (or with another) out of the slots, while the real client is served; with
// switch_node --serve the node pair outlives its clients, one at a time: a second client while one
// is served is told the cluster is busy (at once, not after a timeout), a client that dies does
// not take the nodes with it, and the next client is served with frames equal to the reference.
#include <sys/stat.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <regex>

#include "cluster_run.hpp"

using namespace occtest;
using namespace std::chrono_literals;

namespace {

const std::vector<std::string> kView = {"--width", "160", "--height", "120"};
const std::string kCity = "city:6x6:3:10:1";

std::string write_key(const fs::path& file, char fill) {
  {
    std::ofstream out(file);
    out << std::string(64, fill) << "\n";
  }
  ::chmod(file.c_str(), 0600);
  return file.string();
}

// A render client of the cluster started by `c` (nodes on p0, p1), writing to `out`: what
// Cluster::start_client runs, with its own folder, path and flags.
std::vector<std::string> client_argv(const ClusterOptions& o, int p0, int p1, const fs::path& out,
                                     const std::vector<std::string>& more, const std::string& path = "") {
  fs::create_directories(out);
  std::vector<std::string> a = {bin("render_client"), "--scene", o.scene, "--path", path.empty() ? o.path : path,
                                "--out", out.string(),
                                "--connect", "127.0.0.1:" + std::to_string(p0), "--connect",
                                "127.0.0.1:" + std::to_string(p1), "--timeout-ms", std::to_string(o.timeout_ms),
                                "--occlusion", o.occlusion};
  a.insert(a.end(), o.view.begin(), o.view.end());
  a.insert(a.end(), more.begin(), more.end());
  return a;
}

void expect_equals_reference(const fs::path& reference, const fs::path& out, size_t frames) {
  EXPECT_EQ(frame_count(out), frames) << out;
  const Outcome diff = frame_diff(reference, out);
  EXPECT_EQ(diff.code, 0) << out << ": cluster != reference\n" << differing_frames(diff.log);
  EXPECT_NE(diff_summary(diff.log).find("frames=" + std::to_string(frames)), std::string::npos) << differing_frames(diff.log);
}

// The cluster's first client reaches node 1 through a link_relay, so a test can hold that client
// mid-run (stall) while another process visits the nodes: the session cannot end meanwhile.
struct HeldCluster {
  Cluster c;
  int p0 = 0, p1 = 0;
  HeldCluster(const fs::path& out, const ClusterOptions& o) : c(out, relayed(o)) {}
  static ClusterOptions relayed(ClusterOptions o) {
    o.relay_node1 = true;
    // A hold lasts another process's whole run (its start alone takes seconds under TSan on a
    // loaded machine); the held client and the nodes waiting for each other must outwait it.
    o.timeout_ms = 60000;
    return o;
  }
  bool start() {
    p0 = c.start_node0();
    p1 = c.start_node1();
    if (!p0 || !p1 || !c.start_relay()) return false;
    c.start_client();
    return true;
  }
  bool hold() { return c.control("stall").rfind("ok", 0) == 0; }
  bool release() { return c.control("resume").rfind("ok", 0) == 0; }
};

size_t count(const std::string& s, const std::string& part) {
  size_t n = 0;
  for (size_t p = s.find(part); p != std::string::npos; p = s.find(part, p + 1)) ++n;
  return n;
}

}  // namespace

TEST(Membership, ProcessesWithoutTheKeyAreRefusedWhileTheRealClientIsServed) {
  const fs::path dir = fresh_dir("membership_key");
  const std::string key = write_key(dir / "cluster.key", 'a'), wrong = write_key(dir / "wrong.key", 'b');
  ClusterOptions o(kCity, "walk:60", kView);
  o.all = {"--cluster-key-file", key};
  HeldCluster h(dir / "cluster", o);
  Cluster& c = h.c;
  const int p0 = c.start_node0(), p1 = c.start_node1();
  ASSERT_TRUE(p0 && p1 && c.start_relay()) << c.logs();
  h.p0 = p0;
  h.p1 = p1;

  // Before the real client: one without a key, one with another key. Each is refused at once,
  // saying why (the node's reason in its error, which a timeout could not give), and takes no
  // slot.
  const Outcome nokey = run_to_end(client_argv(o, p0, p1, dir / "nokey", {}), dir / "nokey.log", 60s);
  expect_one_error(nokey, {"the peer speaks TLS: it has a cluster key (--cluster-key-file), this process has none"});
  const Outcome other = run_to_end(client_argv(o, p0, p1, dir / "wrongkey", {"--cluster-key-file", wrong}),
                                   dir / "wrongkey.log", 60s);
  expect_one_error(other, {"TLS handshake failed: cluster key mismatch: the peer rejected the PSK of our key"});
  EXPECT_EQ(frame_count(dir / "nokey") + frame_count(dir / "wrongkey"), 0u);

  // The real client, and while it is served (held mid-run) another one without the key.
  c.start_client();
  ASSERT_TRUE(c.show(5)) << c.logs();
  ASSERT_TRUE(h.hold());
  const Outcome late = run_to_end(client_argv(o, p0, p1, dir / "late", {}), dir / "late.log", 60s);
  ASSERT_TRUE(h.release());
  expect_one_error(late, {"the peer speaks TLS: it has a cluster key"});

  const ClusterRun r = c.finish();
  ASSERT_EQ(r.rvg_code, 0) << r.logs();
  EXPECT_EQ(r.node0_code, 0) << r.node0_log;
  EXPECT_EQ(r.node1_code, 0) << r.node1_log;
  // Logged on the nodes: node 0 saw all three strangers (the clients connect to it first).
  EXPECT_EQ(count(r.node0_log, "TLS handshake failed: the peer speaks no TLS: it has no cluster key"), 2u) << r.node0_log;
  EXPECT_EQ(count(r.node0_log, "TLS handshake failed: cluster key mismatch: the peer has another key"), 1u) << r.node0_log;

  const Outcome ref = run_reference(dir / "reference", kCity, o.path, kView);
  ASSERT_EQ(ref.code, 0) << ref.log;
  expect_equals_reference(dir / "reference", dir / "cluster", 60);
}

TEST(Membership, AKeylessClusterStillWorksAndRefusesAKeyedClient) {
  const fs::path dir = fresh_dir("membership_keyless");
  const std::string key = write_key(dir / "cluster.key", 'a');
  ClusterOptions o(kCity, "walk:10", kView);
  Cluster c(dir / "cluster", o);
  const int p0 = c.start_node0(), p1 = c.start_node1();
  ASSERT_TRUE(p0 && p1) << c.logs();
  const Outcome keyed = run_to_end(client_argv(o, p0, p1, dir / "keyed", {"--cluster-key-file", key}),
                                   dir / "keyed.log", 60s);
  expect_one_error(keyed, {"TLS handshake failed: the peer speaks no TLS: it has no cluster key"});
  c.start_client();
  const ClusterRun r = c.finish();
  EXPECT_EQ(r.rvg_code, 0) << r.logs();
  EXPECT_EQ(r.node0_code, 0) << r.logs();
  EXPECT_EQ(r.node1_code, 0) << r.logs();
  EXPECT_NE(r.node0_log.find("the peer speaks TLS: it has a cluster key (--cluster-key-file), this process has none"),
            std::string::npos) << r.node0_log;
}

TEST(Membership, BadKeyFilesGetOneClearErrorNamingTheFile) {
  const fs::path dir = fresh_dir("membership_keyfiles");
  {
    std::ofstream(dir / "empty.key");
    std::ofstream(dir / "short.key") << "0123456789\n";
  }
  const std::pair<std::string, std::string> cases[] = {
      {(dir / "missing.key").string(), "No such file or directory"},
      {(dir / "empty.key").string(), "is empty"},
      {(dir / "short.key").string(), "is too short: 10 bytes, at least 32"},
      {dir.string(), "is a directory"},
  };
  for (const auto& [file, what] : cases)
    for (const std::vector<std::string>& argv :
         {std::vector<std::string>{bin("switch_node"), "--id", "0", "--scene", kCity},
          std::vector<std::string>{bin("render_client"), "--scene", kCity, "--connect", "127.0.0.1:1"},
          std::vector<std::string>{bin("occlusion_server"), "--scene", kCity}}) {
      std::vector<std::string> a = argv;
      a.insert(a.end(), {"--cluster-key-file", file});
      const Outcome out = run_to_end(a, dir / "run.log", 30s);
      expect_one_error(out, {"--cluster-key-file: cluster key file '" + file + "'", what}, {2, true});
    }
}

TEST(Serve, TheNodesOutliveTheirClientsOneAtATime) {
  const fs::path dir = fresh_dir("serve");
  const std::string key = write_key(dir / "cluster.key", 'c');
  ClusterOptions o(kCity, "walk:60", kView);
  o.all = {"--cluster-key-file", key};
  o.node0 = o.node1 = {"--serve", "3"};
  HeldCluster h(dir / "first", o);
  Cluster& c = h.c;
  ASSERT_TRUE(h.start()) << c.logs();
  const int p0 = h.p0, p1 = h.p1;

  // Client 1 is served; a second client meanwhile (client 1 held mid-run) is told the cluster is
  // busy, at once: node 0's reason is its error, which a timeout could not give (how long the
  // refusal took depends on the machine and is not asserted).
  ASSERT_TRUE(c.show(5)) << c.logs();
  ASSERT_TRUE(h.hold());
  const Outcome busy = run_to_end(client_argv(o, p0, p1, dir / "busy", {"--cluster-key-file", key}),
                                  dir / "busy.log", 60s);
  ASSERT_TRUE(h.release());
  expect_one_error(busy, {"the cluster is busy", "switch_node 0 is serving another render client"});
  ASSERT_EQ(c.client().wait(120s), 0) << c.logs();
  // (A client started before the nodes have closed the last session would be told "busy" too.)
  for (Proc* n : {&c.node0(), &c.node1()}) ASSERT_TRUE(wait_log(*n, "render client 1 done; waiting")) << c.logs();

  // Client 2 dies mid-run (SIGKILL): the nodes end that session and go back to accepting.
  Proc killed(client_argv(o, p0, p1, dir / "killed", {"--cluster-key-file", key}, "walk:100000"), dir / "killed.log");
  ASSERT_GE(wait_frames(dir / "killed" / "stats.csv", 5, 60s, &killed), 5u) << killed.log() << c.logs();
  killed.kill_now();
  killed.wait(10s);
  for (Proc* n : {&c.node0(), &c.node1()}) ASSERT_TRUE(wait_log(*n, "render client 2 failed; waiting")) << c.logs();

  // Client 3 is served from scratch: both nodes reset what they kept for client 2.
  const Outcome third = run_to_end(client_argv(o, p0, p1, dir / "third", {"--cluster-key-file", key}),
                                   dir / "third.log", 120s);
  ASSERT_EQ(third.code, 0) << third.log << c.logs();

  // --serve 3: both nodes end after the third client; one of the three sessions failed.
  const ClusterRun r = c.finish();
  EXPECT_EQ(r.node0_code, 1) << r.node0_log;
  EXPECT_EQ(r.node1_code, 1) << r.node1_log;
  for (const std::string* log : {&r.node0_log, &r.node1_log}) {
    EXPECT_NE(log->find("served 3 render clients (1 failed), as --serve asked"), std::string::npos) << *log;
    EXPECT_NE(log->find("render client 1 done; waiting for the next one (--serve)"), std::string::npos) << *log;
    EXPECT_NE(log->find("render client 2 failed; waiting for the next one (--serve)"), std::string::npos) << *log;
    EXPECT_EQ(count(*log, ": connected: peer "), 3u) << *log;  // a fresh link between the nodes per client
  }
  EXPECT_NE(r.node0_log.find("busy: switch_node 0 is serving another render client"), std::string::npos)
      << r.node0_log;

  const Outcome ref = run_reference(dir / "reference", kCity, o.path, kView);
  ASSERT_EQ(ref.code, 0) << ref.log;
  expect_equals_reference(dir / "reference", dir / "first", 60);
  expect_equals_reference(dir / "reference", dir / "third", 60);
  // The third client's statistics match the first's frame for frame: nothing carried over.
  auto a = read_csv(dir / "first" / "stats.csv"), b = read_csv(dir / "third" / "stats.csv");
  EXPECT_EQ(a["visible"], b["visible"]);
  EXPECT_EQ(a["added"], b["added"]);
}

// A node's summary of a client counts that client's frames only (each client gets a
// fresh session: nothing is reset by hand, so no counter can be forgotten). Two clients one after
// the other, neither with occlusion (--occlusion frustum): every HC frame of each is a frustum
// set, so each summary's frames without occlusion equal its own HC frames.
TEST(Serve, EachClientsSummaryCountsOnlyItsOwnFrames) {
  const fs::path dir = fresh_dir("serve_summary");
  ClusterOptions o(kCity, "walk:10", kView);
  o.occlusion = "frustum";
  o.client = {"--images", "off"};
  o.node0 = o.node1 = {"--serve", "2"};
  Cluster c(dir / "first", o);
  const int p0 = c.start_node0(), p1 = c.start_node1();
  ASSERT_TRUE(p0 && p1) << c.logs();
  c.start_client();
  ASSERT_EQ(c.client().wait(120s), 0) << c.logs();
  for (Proc* n : {&c.node0(), &c.node1()}) ASSERT_TRUE(wait_log(*n, "render client 1 done; waiting")) << c.logs();
  const Outcome second = run_to_end(client_argv(o, p0, p1, dir / "second", {"--images", "off"}), dir / "second.log", 120s);
  ASSERT_EQ(second.code, 0) << second.log << c.logs();
  const ClusterRun r = c.finish();
  const std::regex summary(R"((\d+) HC frames, .*\); (\d+) frames without occlusion)");
  for (const std::string* log : {&r.node0_log, &r.node1_log}) {
    std::vector<std::pair<unsigned long, unsigned long>> found;  // (HC frames, frames without occlusion)
    for (auto it = std::sregex_iterator(log->begin(), log->end(), summary); it != std::sregex_iterator(); ++it)
      found.emplace_back(std::stoul((*it)[1]), std::stoul((*it)[2]));
    ASSERT_EQ(found.size(), 2u) << *log;
    for (const auto& [frames, without] : found) {
      EXPECT_EQ(frames, 5u) << "half of the 10 frames of each client\n" << *log;
      EXPECT_EQ(without, frames) << "this client's frames only\n" << *log;
    }
  }
}
