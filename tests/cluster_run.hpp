// The occlusion switch's three real processes on 127.0.0.1, like scripts/cluster.sh: switch node 0,
// switch node 1 (its peer) and the render client connected to both, each with a port file and a
// log in one directory (node0.log, node1.log, render_client.log). What differs between the tests
// is in ClusterOptions: flags for all or for one process, timeouts, and a link_relay (with a
// control port) between the render client and node 1. run_cluster() runs it to the end; a test
// that acts while it runs (kills a node, cuts the link, sends strangers to a port) uses Cluster
// step by step.
#pragma once
#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>

#include <optional>

#include "integration_util.hpp"

namespace occtest {

struct ClusterOptions {
  ClusterOptions(std::string scene_, std::string path_, std::vector<std::string> view_)
      : scene(std::move(scene_)), path(std::move(path_)), view(std::move(view_)) {}
  std::string scene;                               // --scene of all three ("": the per-process flags name it)
  std::string path;                                // the render client's --path
  std::vector<std::string> view;                   // --width W --height H of all three
  int timeout_ms = 20000;                          // --timeout-ms of all three
  std::vector<std::string> all;                    // more flags for all three
  std::vector<std::string> node0, node1, client;   // more flags for one of them
  // The render client's --occlusion: "switch" (every frame with occlusion by the switch) keeps
  // the runs of the switch's own tests deterministic; the gate's tests set it.
  std::string occlusion = "switch";
  bool relay_node1 = false;                        // the client reaches node 1 through link_relay
  bool relay_node_link = false;                    // or: node 1 reaches node 0 through link_relay
  std::chrono::milliseconds client_wait = std::chrono::seconds(300);  // finish(): the client's end
  std::chrono::milliseconds node_wait = std::chrono::seconds(30);     // then each node's
};

struct ClusterRun {
  int rvg_code = -1, node0_code = -1, node1_code = -1;
  std::string rvg_log, node0_log, node1_log;
  std::string logs() const {
    return "--- render_client\n" + rvg_log + "--- node 0\n" + node0_log + "--- node 1\n" + node1_log;
  }
};

class Cluster {
 public:
  Cluster(fs::path out, ClusterOptions o) : out_(std::move(out)), o_(std::move(o)) { fs::create_directories(out_); }

  // Each start returns the port its process wrote (0 if it ended first or never wrote it).
  int start_node0() {
    n0_.emplace(args({bin("switch_node"), "--id", "0", "--port-file", file("n0.port")}, o_.node0), out_ / "node0.log");
    return p0_ = wait_port(out_ / "n0.port", *n0_);
  }
  int start_node1() {
    n1_.emplace(args({bin("switch_node"), "--id", "1", "--peer", local(o_.relay_node_link ? pr_ : p0_), "--port-file",
                      file("n1.port")},
                     o_.node1),
                out_ / "node1.log");
    return p1_ = wait_port(out_ / "n1.port", *n1_);
  }
  // Switch node k once more after it died, as an operator restarts it: the same flags, the same
  // port (the render client and node 1 reach it where they did), its own log (nodeK_again.log).
  // Returns the port it wrote (0 if it ended first).
  int restart_node(int k) {
    auto& p = k == 0 ? n0_again_ : n1_again_;
    const std::string port = std::to_string(k == 0 ? p0_ : p1_), pf = file("n" + std::to_string(k) + "_again.port");
    std::vector<std::string> a = {bin("switch_node"), "--id", std::to_string(k), "--listen", "127.0.0.1:" + port,
                                  "--port-file", pf};
    if (k == 1) a.insert(a.end(), {"--peer", local(p0_)});
    p.emplace(args(a, k == 0 ? o_.node0 : o_.node1), out_ / ("node" + std::to_string(k) + "_again.log"));
    return wait_port(pf, *p);
  }
  Proc& restarted(int k) { return k == 0 ? *n0_again_ : *n1_again_; }

  // link_relay in front of node 1 (relay_node1), or of node 0 for node 1 (relay_node_link);
  // control() sends its control port "stall", "cut", ... (see relay_test).
  int start_relay() {
    const int target = o_.relay_node_link ? p0_ : p1_;
    relay_.emplace(std::vector<std::string>{bin("link_relay"), "--target", local(target), "--port-file", file("relay.port"),
                                            "--control-port-file", file("control.port")},
                   out_ / "relay.log");
    pr_ = wait_port(out_ / "relay.port", *relay_);
    pc_ = wait_port(out_ / "control.port", *relay_);
    return pr_ && pc_ ? pr_ : 0;
  }
  void start_client() {
    client_.emplace(args({bin("render_client"), "--path", o_.path, "--out", out_.string(), "--connect", local(p0_),
                          "--connect", local(o_.relay_node1 ? pr_ : p1_), "--occlusion", o_.occlusion},
                         o_.client),
                    out_ / "render_client.log");
  }
  // Node 0, node 1, the relay if asked for, then the client once every port is known: whether
  // the client was started.
  bool start() {
    start_node0();
    if (o_.relay_node_link && (!p0_ || !start_relay())) return false;
    start_node1();
    if (!p0_ || !p1_ || (o_.relay_node1 && !start_relay())) return false;
    start_client();
    return true;
  }
  // start(), then a wait until the client has shown `frames` frames (60 s at most, and no longer
  // than it runs): whether it got that far.
  bool start_and_show(size_t frames) { return start() && show(frames); }
  // A wait until the started client has shown `frames` frames in all (as start_and_show), or
  // `more` frames more than now: whether it got that far.
  bool show(size_t frames) { return wait_frames(stats(), frames, std::chrono::seconds(60), &*client_) >= frames; }
  bool show_more(size_t more) { return show(read_csv(stats())["frame"].size() + more); }

  // One command on the relay's control port ("stall", "resume", "cut", ...): its one-line answer
  // ("ok ..." when done; "" when the port did not answer).
  std::string control(const std::string& command) const {
    const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_port = htons(uint16_t(pc_));
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    std::string reply;
    if (::connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) == 0) {
      const std::string line = command + "\n";
      (void)!::write(fd, line.data(), line.size());
      char c;
      while (::read(fd, &c, 1) == 1 && c != '\n') reply += c;
    }
    ::close(fd);
    return reply;
  }
  // Waits for the client (client_wait), then for each node (node_wait): exit codes and logs.
  ClusterRun finish() {
    ClusterRun r;
    if (client_) {
      r.rvg_code = client_->wait(o_.client_wait);
      r.rvg_log = client_->log();
    }
    if (n0_) {
      r.node0_code = n0_->wait(o_.node_wait);
      r.node0_log = n0_->log();
    }
    if (n1_) {
      r.node1_code = n1_->wait(o_.node_wait);
      r.node1_log = n1_->log();
    }
    return r;
  }

  // The logs of the processes started so far, for failure messages.
  std::string logs() const {
    const std::pair<const char*, const std::optional<Proc>*> procs[] = {
        {"node 0", &n0_},         {"node 1", &n1_},
        {"node 0 restarted", &n0_again_}, {"node 1 restarted", &n1_again_},
        {"link_relay", &relay_},  {"render_client", &client_}};
    std::string s;
    for (const auto& [name, p] : procs)
      if (*p) s += std::string("--- ") + name + "\n" + (*p)->log();
    return s;
  }

  Proc& node0() { return *n0_; }
  Proc& node1() { return *n1_; }
  Proc& client() { return *client_; }
  Proc& relay() { return *relay_; }
  const fs::path& out() const { return out_; }
  fs::path stats() const { return out_ / "stats.csv"; }

 private:
  static std::string local(int port) { return "127.0.0.1:" + std::to_string(port); }
  std::string file(const std::string& name) const { return (out_ / name).string(); }
  // A process's own flags, then the scene, timeout, view and flags of all three, then its extra flags.
  std::vector<std::string> args(std::vector<std::string> a, const std::vector<std::string>& more) const {
    if (!o_.scene.empty()) a.insert(a.end(), {"--scene", o_.scene});
    a.insert(a.end(), {"--timeout-ms", std::to_string(o_.timeout_ms)});
    for (const auto* v : {&o_.view, &o_.all, &more}) a.insert(a.end(), v->begin(), v->end());
    return a;
  }

  fs::path out_;
  ClusterOptions o_;
  int p0_ = 0, p1_ = 0, pr_ = 0, pc_ = 0;
  std::optional<Proc> n0_, n1_, relay_, client_, n0_again_, n1_again_;
};

// The whole run: start, then finish (the client is not started when a node wrote no port).
inline ClusterRun run_cluster(const fs::path& out, ClusterOptions o) {
  Cluster c(out, std::move(o));
  c.start();
  return c.finish();
}

// The render client of a running cluster stops on a fault of node 1 or its link: exit 1 (the
// test waits 30 s), with an error naming the frame and switch node 1. What ended it is read from
// that error, not from a clock (a loaded machine may take its time): `timed_out`, its own receive
// timeout ("sent nothing for N ms"), else the disconnect, never the timeout. Returns its log.
inline std::string expect_client_stops_naming_node1(Proc& client, bool timed_out) {
  const int code = client.wait(std::chrono::seconds(30));
  const std::string log = client.log();
  EXPECT_EQ(code, 1) << log;
  const size_t at = log.find("error: render_client: frame ");
  EXPECT_NE(at, std::string::npos) << log;
  EXPECT_NE(log.find("switch node 1"), std::string::npos) << log;
  const std::string error = at == std::string::npos ? "" : log.substr(at, log.find('\n', at) - at);
  EXPECT_EQ(error.find(") sent nothing for ") != std::string::npos, timed_out) << log;
  return log;
}

// Waits (at most `timeout`) until `p`'s log contains `text`.
inline bool wait_log(Proc& p, const std::string& text, std::chrono::milliseconds timeout = std::chrono::seconds(60)) {
  const auto end = std::chrono::steady_clock::now() + timeout;
  while (p.log().find(text) == std::string::npos) {
    if (std::chrono::steady_clock::now() > end) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  return true;
}

// Every frame file in `out` is complete (no .tmp left) and has its row in stats.csv.
inline void expect_no_partial_frames(const fs::path& out) {
  size_t frames = 0;
  for (auto& e : fs::directory_iterator(out)) {
    const std::string name = e.path().filename().string();
    EXPECT_EQ(name.find(".tmp"), std::string::npos) << name;
    frames += name.rfind("frame_", 0) == 0;
  }
  EXPECT_EQ(frames, read_csv(out / "stats.csv")["frame"].size());
}

// The main check of the cluster and hard-case tests: the cluster renders exactly what the
// reference renderer (with `reference_flags`) renders, every one of `frames` frames (frame_diff
// --max-fraction 0.0001). Runs in dir/cluster and dir/reference; returns the run for more checks,
// or nothing when the client or the reference failed (then there is nothing to compare).
inline std::optional<ClusterRun> expect_cluster_equals_reference(const fs::path& dir, const ClusterOptions& o,
                                                                 const std::vector<std::string>& reference_flags,
                                                                 size_t frames) {
  ClusterRun r = run_cluster(dir / "cluster", o);
  EXPECT_EQ(r.rvg_code, 0) << r.logs();
  EXPECT_EQ(r.node0_code, 0) << r.logs();
  EXPECT_EQ(r.node1_code, 0) << r.logs();
  const Outcome ref = run_reference(dir / "reference", o.scene, o.path, reference_flags);
  EXPECT_EQ(ref.code, 0) << ref.log;
  if (r.rvg_code != 0 || ref.code != 0) return std::nullopt;
  EXPECT_EQ(frame_count(dir / "cluster"), frames);
  const Outcome diff = frame_diff(dir / "reference", dir / "cluster");
  EXPECT_EQ(diff.code, 0) << dir.filename() << ": cluster != reference\n" << differing_frames(diff.log);
  EXPECT_NE(diff_summary(diff.log).find("frames=" + std::to_string(frames)), std::string::npos) << differing_frames(diff.log);
  return r;
}

}  // namespace occtest
