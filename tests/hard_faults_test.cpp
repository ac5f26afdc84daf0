// Faults and bad input at the listening ports of the real switch nodes: random bytes,
// a client that connects and says nothing, a peer speaking another protocol version. Each is
// refused with a logged reason naming the stranger's address ("occ_net: peer 127.0.0.1:PORT:
// <reason>"), and the node keeps serving its real peers: the cluster run then completes with
// exit 0 and frames equal to the reference.
#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>

#include <gtest/gtest.h>

#include <random>

#include "hard_util.hpp"
#include "protocol/wire.hpp"

using namespace occtest;
using occ::Camera;

namespace {

// A raw TCP client of 127.0.0.1:port (no handshake of its own).
class Stranger {
 public:
  explicit Stranger(int port) {
    fd_ = ::socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_port = htons(uint16_t(port));
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    connected_ = ::connect(fd_, reinterpret_cast<sockaddr*>(&a), sizeof a) == 0;
    sockaddr_in me{};
    socklen_t len = sizeof me;
    if (connected_ && ::getsockname(fd_, reinterpret_cast<sockaddr*>(&me), &len) == 0) port_ = ntohs(me.sin_port);
  }
  ~Stranger() { close(); }
  bool connected() const { return connected_; }
  int local_port() const { return port_; }
  void send(const std::vector<uint8_t>& bytes) {
    size_t off = 0;
    while (off < bytes.size()) {
      const ssize_t n = ::send(fd_, bytes.data() + off, bytes.size() - off, MSG_NOSIGNAL);
      if (n <= 0) return;  // the node may already have hung up on us
      off += size_t(n);
    }
  }
  // Everything the node sends until it closes (or `timeout`).
  std::string read_until_closed(std::chrono::milliseconds timeout) {
    std::string got;
    const auto end = std::chrono::steady_clock::now() + timeout;
    for (;;) {
      const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(end - std::chrono::steady_clock::now());
      if (left.count() <= 0) break;
      pollfd p{fd_, POLLIN, 0};
      if (::poll(&p, 1, int(left.count())) <= 0) break;
      char buf[4096];
      const ssize_t n = ::recv(fd_, buf, sizeof buf, 0);
      if (n <= 0) break;
      got.append(buf, size_t(n));
    }
    return got;
  }
  void close() {
    if (fd_ >= 0) ::close(fd_);
    fd_ = -1;
  }

 private:
  int fd_ = -1, port_ = 0;
  bool connected_ = false;
};

std::vector<uint8_t> random_bytes(uint32_t seed, size_t n) {
  std::mt19937 rng(seed);
  std::vector<uint8_t> b(n);
  for (auto& x : b) x = uint8_t(rng());
  return b;
}

// A well-formed Hello of a render client, with the version field (frame offset 6 + 4) patched.
std::vector<uint8_t> hello_with_version(uint16_t version) {
  occ::wire::Hello h;
  h.role = occ::wire::Role::render_client;
  h.name = "time traveller";
  std::vector<uint8_t> bytes = occ::wire::encode(occ::wire::Message{h});
  bytes[10] = uint8_t(version & 0xff);
  bytes[11] = uint8_t(version >> 8);
  return bytes;
}

// The log line about the connection from local port `port`, or "".
std::string line_about(const std::string& log, int port) {
  const std::string key = "127.0.0.1:" + std::to_string(port) + ":";
  const size_t at = log.find(key);
  if (at == std::string::npos) return "";
  const size_t begin = log.rfind('\n', at) == std::string::npos ? 0 : log.rfind('\n', at) + 1;
  return log.substr(begin, log.find('\n', at) - begin);
}

struct Strangers {
  Stranger garbage_small, garbage_big, silent, wrong_version;
  std::string wrong_version_reply;
};

// Sends the three kinds of strangers to a listening port (they are handled one after the other).
std::unique_ptr<Strangers> visit(int port, uint32_t seed) {
  auto s = std::unique_ptr<Strangers>(new Strangers{Stranger(port), Stranger(port), Stranger(port), Stranger(port), {}});
  s->garbage_small.send(random_bytes(seed, 64));
  s->garbage_small.close();
  s->garbage_big.send(random_bytes(seed + 1, 1 << 16));
  s->garbage_big.close();
  s->wrong_version.send(hello_with_version(occ::wire::kProtocolVersion + 6));
  // The silent one stays connected, saying nothing, until the node gives up on it.
  return s;
}

void expect_refused(const std::string& log, const Strangers& s, const std::string& who) {
  for (const Stranger* x : {&s.garbage_small, &s.garbage_big, &s.silent, &s.wrong_version})
    EXPECT_TRUE(x->connected()) << who;
  const std::string small = line_about(log, s.garbage_small.local_port()),
                    big = line_about(log, s.garbage_big.local_port()), silent = line_about(log, s.silent.local_port()),
                    version = line_about(log, s.wrong_version.local_port());
  std::cout << "[ figures  ] " << who << " refused:\n  " << small << "\n  " << big << "\n  " << silent << "\n  "
            << version << "\n";
  EXPECT_NE(small.find("occ_net: peer"), std::string::npos) << who << " random bytes (64 B) not logged\n" << log;
  EXPECT_NE(big.find("occ_net: peer"), std::string::npos) << who << " random bytes (64 KiB) not logged\n" << log;
  EXPECT_NE(silent.find("no hello within"), std::string::npos) << who << " silent client\n" << log;
  EXPECT_NE(version.find("version"), std::string::npos) << who << " wrong protocol version\n" << log;
}

}  // namespace

TEST(HardFaults, StrangersAtEveryListeningPortAreRefusedWithAReasonAndTheClusterStillServes) {
  const View view{64, 48};
  const std::string scene = "hard:walls:2";
  const fs::path dir = fresh_dir("hard_faults");
  const fs::path out = dir / "cluster";
  std::vector<Camera> path;
  for (int i = 0; i < 30; ++i) path.push_back(cam({-12.0 + i, 1.5, 0.1 * i}, {30, 1.5, 0}));
  const std::string csv = write_path(dir / "path.csv", path);

  ClusterOptions o = hard_cluster(scene, csv, view);
  o.timeout_ms = 20000;
  o.client_wait = 120s;
  o.node_wait = 30s;
  Cluster c(out, o);
  const int p0 = c.start_node0();
  ASSERT_NE(p0, 0) << c.node0().log();
  auto at0 = visit(p0, 1);
  at0->wrong_version_reply = at0->wrong_version.read_until_closed(10s);

  const int p1 = c.start_node1();
  ASSERT_NE(p1, 0) << c.node1().log();
  auto at1 = visit(p1, 2);

  c.start_client();
  at1->wrong_version_reply = at1->wrong_version.read_until_closed(10s);
  // While frames flow the listening ports stay open (a second render client is told the cluster
  // is busy): more random bytes there (refused with a logged reason) must not disturb the run.
  wait_frames(c.stats(), 5, 60s, &c.client());  // (the client's start: seconds under TSan on a loaded machine)
  for (int port : {p0, p1}) {
    Stranger late(port);
    late.send(random_bytes(3, 256));
  }
  const ClusterRun r = c.finish();
  ASSERT_EQ(r.rvg_code, 0) << r.logs();
  EXPECT_EQ(r.node0_code, 0) << r.node0_log;
  EXPECT_EQ(r.node1_code, 0) << r.node1_log;

  expect_refused(r.node0_log, *at0, "switch node 0");
  expect_refused(r.node1_log, *at1, "switch node 1");
  // The stranger with another version was told why (its Bye; the node answers a hello it cannot
  // read with no hello of its own).
  EXPECT_NE(at0->wrong_version_reply.find("version"), std::string::npos);
  EXPECT_NE(at1->wrong_version_reply.find("version"), std::string::npos);

  const Outcome ref = run_reference(dir / "reference", scene, csv, unculled(view));
  ASSERT_EQ(ref.code, 0) << ref.log;
  const Outcome diff = frame_diff(dir / "reference", out);
  EXPECT_EQ(diff.code, 0) << differing_frames(diff.log);
  EXPECT_EQ(frame_count(out), path.size());
}
