// Link emulator: occ_relay in-process between a client socket and a loopback echo server
// (delay, rate, integrity under jitter, stall/resume, cut, late or absent target), then the
// link_relay binary (bad flags, port files, control port). Measured figures go to stdout.
// 127.0.0.1 and port 0 only; every wait is bounded.
#include <arpa/inet.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cstring>
#include <functional>
#include <mutex>
#include <optional>
#include <random>

#include <gtest/gtest.h>

#include "integration_util.hpp"
#include "protocol/relay/relay.hpp"

using namespace occ;
using namespace std::chrono_literals;
using Clock = std::chrono::steady_clock;
using Bytes = std::vector<uint8_t>;

namespace {

// Every test here takes seconds: a hang must fail the test, not stall the suite.
const bool watchdog = [] {
  std::thread([] {
    std::this_thread::sleep_for(60s);
    std::cerr << "relay_test: watchdog: still running after 60 s\n";
    std::abort();
  }).detach();
  return true;
}();

double ms_since(Clock::time_point t0) { return std::chrono::duration<double, std::milli>(Clock::now() - t0).count(); }

Bytes random_bytes(size_t n, uint64_t seed) {
  Bytes b(n);
  std::mt19937_64 rng(seed);
  for (size_t i = 0; i < n; i += 8) {
    const uint64_t v = rng();
    std::memcpy(b.data() + i, &v, std::min<size_t>(8, n - i));
  }
  return b;
}

uint64_t fnv1a(const Bytes& b) {
  uint64_t h = 0xcbf29ce484222325ull;
  for (uint8_t c : b) h = (h ^ c) * 0x100000001b3ull;
  return h;
}

sockaddr_in loopback(uint16_t port) {
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(port);
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  return a;
}

// A port nobody listens on (bound, then released).
uint16_t unused_port() {
  int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in a = loopback(0);
  socklen_t len = sizeof a;
  ::bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a);
  ::getsockname(fd, reinterpret_cast<sockaddr*>(&a), &len);
  ::close(fd);
  return ntohs(a.sin_port);
}

// Blocking client socket: TCP_NODELAY, 5 s send/receive timeouts.
class Sock {
 public:
  explicit Sock(uint16_t port) : fd_(::socket(AF_INET, SOCK_STREAM, 0)) {
    int one = 1;
    ::setsockopt(fd_, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
    timeval tv{5, 0};
    ::setsockopt(fd_, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
    ::setsockopt(fd_, SOL_SOCKET, SO_SNDTIMEO, &tv, sizeof tv);
    sockaddr_in a = loopback(port);
    connected_ = ::connect(fd_, reinterpret_cast<sockaddr*>(&a), sizeof a) == 0;
  }
  ~Sock() { ::close(fd_); }
  Sock(const Sock&) = delete;
  Sock& operator=(const Sock&) = delete;

  bool connected() const { return connected_; }
  bool send_all(const uint8_t* p, size_t n) {
    while (n > 0) {
      ssize_t k = ::send(fd_, p, n, MSG_NOSIGNAL);
      if (k <= 0) return false;
      p += k;
      n -= size_t(k);
    }
    return true;
  }
  bool send_all(const std::string& s) { return send_all(reinterpret_cast<const uint8_t*>(s.data()), s.size()); }
  // Exactly n bytes, or false on EOF, error or timeout.
  bool recv_exact(uint8_t* p, size_t n) {
    while (n > 0) {
      ssize_t k = ::recv(fd_, p, n, 0);
      if (k <= 0) return false;
      p += k;
      n -= size_t(k);
    }
    return true;
  }
  Bytes recv_exact(size_t n) {
    Bytes b(n);
    if (!recv_exact(b.data(), n)) b.clear();
    return b;
  }
  // True when the peer closed (EOF or reset) within the receive timeout; data is an error.
  bool sees_close() {
    uint8_t c;
    ssize_t k = ::recv(fd_, &c, 1, 0);
    return k == 0 || (k < 0 && errno != EAGAIN && errno != EWOULDBLOCK);
  }
  bool has_data_now() {
    uint8_t c;
    return ::recv(fd_, &c, 1, MSG_DONTWAIT | MSG_PEEK) > 0;
  }
  std::string line() {
    std::string s;
    for (uint8_t c; recv_exact(&c, 1) && c != '\n';) s += char(c);
    return s;
  }
  void shutdown_write() { ::shutdown(fd_, SHUT_WR); }

 private:
  int fd_;
  bool connected_ = false;
};

// Echoes every connection on 127.0.0.1 (one thread each); on EOF shuts the connection down.
class EchoServer {
 public:
  explicit EchoServer(uint16_t port = 0) : listen_fd_(::socket(AF_INET, SOCK_STREAM, 0)) {
    int one = 1;
    ::setsockopt(listen_fd_, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
    sockaddr_in a = loopback(port);
    socklen_t len = sizeof a;
    ::bind(listen_fd_, reinterpret_cast<sockaddr*>(&a), sizeof a);
    ::listen(listen_fd_, 16);
    ::getsockname(listen_fd_, reinterpret_cast<sockaddr*>(&a), &len);
    port_ = ntohs(a.sin_port);
    accept_thread_ = std::thread([this] { accept_loop(); });
  }
  ~EchoServer() {
    stop_ = true;
    accept_thread_.join();  // no new connections from here on
    for (int fd : fds_) ::shutdown(fd, SHUT_RDWR);
    for (auto& t : echo_threads_) t.join();
    for (int fd : fds_) ::close(fd);
    ::close(listen_fd_);
  }

  uint16_t port() const { return port_; }
  uint64_t received() const { return received_; }
  int closed() const { return closed_; }

 private:
  void accept_loop() {
    while (!stop_) {
      pollfd p{listen_fd_, POLLIN, 0};
      if (::poll(&p, 1, 20) <= 0) continue;
      int fd = ::accept(listen_fd_, nullptr, nullptr);
      if (fd < 0) continue;
      int one = 1;
      ::setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
      fds_.push_back(fd);
      echo_threads_.emplace_back([this, fd] { echo(fd); });
    }
  }
  void echo(int fd) {
    std::vector<uint8_t> buf(64 * 1024);
    for (;;) {
      ssize_t n = ::recv(fd, buf.data(), buf.size(), 0);
      if (n <= 0) break;
      received_ += uint64_t(n);
      if (::send(fd, buf.data(), size_t(n), MSG_NOSIGNAL) != n) break;  // blocking: all or error
    }
    ::shutdown(fd, SHUT_RDWR);
    ++closed_;
  }

  int listen_fd_;
  uint16_t port_ = 0;
  std::atomic<bool> stop_{false};
  std::atomic<uint64_t> received_{0};
  std::atomic<int> closed_{0};
  std::thread accept_thread_;
  std::vector<int> fds_;                    // accept thread until it is joined
  std::vector<std::thread> echo_threads_;  // likewise
};

struct LogLines {
  std::mutex m;
  std::vector<std::string> lines;
  void add(const std::string& line) {
    std::lock_guard lk(m);
    lines.push_back(line);
  }
  bool contains(const std::string& s) {
    std::lock_guard lk(m);
    return std::any_of(lines.begin(), lines.end(), [&](auto& l) { return l.find(s) != std::string::npos; });
  }
};

relay::RelayOptions options(uint16_t target_port, LogLines& log) {
  relay::RelayOptions o;
  o.target_port = target_port;
  o.log = [&log](const std::string& line) { log.add(line); };
  return o;
}

uint64_t stat(const std::string& line, const std::string& key) {
  auto at = (" " + line).find(" " + key + "=");
  return at == std::string::npos ? UINT64_MAX : std::stoull(line.substr(at + key.size() + 1));
}

template <class Pred>
bool eventually(Pred pred, std::chrono::milliseconds timeout = 2s) {
  const auto end = Clock::now() + timeout;
  while (!pred()) {
    if (Clock::now() > end) return false;
    std::this_thread::sleep_for(5ms);
  }
  return true;
}

// Sends `data` from a thread while the caller reads the echo; returns the echo (empty on failure).
Bytes echo_through(Sock& s, const Bytes& data, uint64_t seed) {
  std::thread writer([&] {
    std::mt19937 rng{uint32_t(seed)};
    for (size_t at = 0; at < data.size();) {
      const size_t n = std::min<size_t>(data.size() - at, 1 + rng() % 100000);
      if (!s.send_all(data.data() + at, n)) return;
      at += n;
    }
  });
  Bytes back = s.recv_exact(data.size());
  writer.join();
  return back;
}

// A relay in front of a loopback echo server (or the target port given); each test tunes the
// options.
class Relay : public testing::Test {
 protected:
  void start(const std::function<void(relay::RelayOptions&)>& tune, uint16_t target_port = 0) {
    relay::RelayOptions o = options(target_port ? target_port : echo.port(), log);
    tune(o);
    auto started = relay::Relay::start(o);
    ASSERT_TRUE(started) << started.error();
    r.emplace(std::move(*started));
  }
  EchoServer echo;
  LogLines log;
  std::optional<relay::Relay> r;
};

TEST_F(Relay, DelayAddsToTheRoundTrip) {
  ASSERT_NO_FATAL_FAILURE(start([](auto& o) { o.up.delay_ms = o.down.delay_ms = 20; }));
  Sock c(r->port());
  ASSERT_TRUE(c.connected());
  std::vector<double> rtt;
  const Bytes ping = random_bytes(32, 1);
  for (int i = 0; i < 5; ++i) {
    const auto t0 = Clock::now();
    ASSERT_TRUE(c.send_all(ping.data(), ping.size()));
    ASSERT_EQ(c.recv_exact(ping.size()), ping);
    rtt.push_back(ms_since(t0));
  }
  std::sort(rtt.begin(), rtt.end());
  std::cout << "delay 20 ms each way: round trip min " << rtt.front() << " median " << rtt[2] << " max "
            << rtt.back() << " ms\n";
  EXPECT_GE(rtt.front(), 40.0);
  EXPECT_LT(rtt.back(), 100.0);
}

TEST_F(Relay, RateCapsThroughput) {
  ASSERT_NO_FATAL_FAILURE(start([](auto& o) { o.up.rate_mbit = o.down.rate_mbit = 40; }));
  Sock c(r->port());
  ASSERT_TRUE(c.connected());
  const Bytes data = random_bytes(2'000'000, 2);
  const auto t0 = Clock::now();
  EXPECT_EQ(echo_through(c, data, 2), data);
  const double s = ms_since(t0) / 1000;
  std::cout << "2 MB echoed through 40 Mbit/s each way: " << s << " s (ideal 0.4 s), " << 16.0 / s
            << " Mbit/s\n";
  EXPECT_GE(s, 0.4 * 0.9);
  EXPECT_LT(s, 0.4 * 3);
}

TEST_F(Relay, JitterNeverCorruptsOrReorders) {
  ASSERT_NO_FATAL_FAILURE(start([](auto& o) {
    o.up = o.down = {2, 2, 0};  // releases spread over up to 4 ms
    o.max_queued_bytes = 1u << 20;
    o.seed = 7;
  }));
  constexpr size_t kBytes = 20'000'000;
  const auto t0 = Clock::now();
  std::vector<std::thread> clients;
  std::atomic<int> good{0};
  for (uint64_t k = 0; k < 2; ++k)
    clients.emplace_back([&, k] {  // two connections at once, each echoing 20 MB
      Sock c(r->port());
      const Bytes data = random_bytes(kBytes, 10 + k);
      const Bytes back = echo_through(c, data, k);
      c.shutdown_write();
      if (back.size() == kBytes && fnv1a(back) == fnv1a(data) && c.sees_close()) ++good;
    });
  for (auto& t : clients) t.join();
  std::cout << "2 x 20 MB echoed with 2 +- 2 ms jitter in " << ms_since(t0) << " ms\n";
  EXPECT_EQ(good, 2);
  ASSERT_TRUE(eventually([&] { return r->stats().open == 0; }));
  const auto st = r->stats();
  EXPECT_EQ(st.up_bytes, 2 * kBytes);
  EXPECT_EQ(st.down_bytes, 2 * kBytes);
  EXPECT_TRUE(log.contains("conn 1 closed (eof) up 20000000 B down 20000000 B"));
  EXPECT_TRUE(log.contains("conn 2 closed (eof) up 20000000 B down 20000000 B"));
}

TEST_F(Relay, StallHoldsEverythingUntilResume) {
  ASSERT_NO_FATAL_FAILURE(start([](auto& o) {
    o.control = true;
    o.max_queued_bytes = 1u << 20;
  }));
  Sock ctl(r->control_port()), c(r->port());
  ASSERT_TRUE(ctl.connected() && c.connected());
  ASSERT_EQ(echo_through(c, {42}, 0), Bytes{42});

  ASSERT_TRUE(ctl.send_all("stall\n"));
  EXPECT_EQ(ctl.line(), "ok stalled");
  const Bytes data = random_bytes(4 << 20, 3);
  std::thread writer([&] { c.send_all(data.data(), data.size()); });
  std::this_thread::sleep_for(300ms);
  EXPECT_EQ(echo.received(), 1u);  // the first byte only
  EXPECT_FALSE(c.has_data_now());
  ASSERT_TRUE(ctl.send_all("stats\n"));
  const std::string stalled = ctl.line();
  std::cout << "stalled: " << stalled << "\n";
  EXPECT_EQ(stat(stalled, "stalled"), 1u);
  EXPECT_GT(stat(stalled, "queued_up"), 0u);
  EXPECT_LE(stat(stalled, "queued_up"), (1u << 20) + 64 * 1024);  // bounded: the sender is pushed back

  const auto t0 = Clock::now();
  ASSERT_TRUE(ctl.send_all("resume\n"));
  EXPECT_EQ(ctl.line(), "ok resumed");
  EXPECT_EQ(c.recv_exact(data.size()), data);
  writer.join();
  std::cout << "4 MiB delivered " << ms_since(t0) << " ms after resume\n";
  ASSERT_TRUE(ctl.send_all("stats\n"));
  const std::string after = ctl.line();
  EXPECT_EQ(stat(after, "up"), data.size() + 1);
  EXPECT_EQ(stat(after, "down"), data.size() + 1);
  ASSERT_TRUE(ctl.send_all("bogus\n"));
  EXPECT_EQ(ctl.line(), "error: unknown command 'bogus' (stall|resume|cut|flip|stats)");
}

TEST_F(Relay, FlipAltersOneByteOfTheNextChunkFromTheTargetOnly) {
  ASSERT_NO_FATAL_FAILURE(start([](auto& o) { o.control = true; }));
  Sock ctl(r->control_port()), c(r->port());
  ASSERT_TRUE(ctl.send_all("flip\n"));
  EXPECT_EQ(ctl.line(), "ok flip armed");
  const Bytes sent{10, 20, 30, 40, 50, 60, 70, 80};
  const Bytes back = echo_through(c, sent, 0);  // up intact (the echo answers it), down altered
  ASSERT_EQ(back.size(), sent.size());
  size_t differing = 0;
  for (size_t i = 0; i < sent.size(); ++i)
    if (back[i] != sent[i]) {
      ++differing;
      EXPECT_EQ(back[i] ^ sent[i], 0x01);
    }
  EXPECT_EQ(differing, 1u);
  EXPECT_EQ(echo_through(c, sent, 0), sent) << "once only";
}

TEST_F(Relay, CutClosesBothSidesAndKeepsListening) {
  ASSERT_NO_FATAL_FAILURE(start([](auto& o) { o.control = true; }));
  Sock ctl(r->control_port()), c(r->port());
  ASSERT_EQ(echo_through(c, {1, 2, 3}, 0), (Bytes{1, 2, 3}));

  const auto t0 = Clock::now();
  ASSERT_TRUE(ctl.send_all("cut\n"));
  EXPECT_EQ(ctl.line(), "ok cut 1");
  EXPECT_TRUE(c.sees_close());
  const double client_ms = ms_since(t0);
  EXPECT_TRUE(eventually([&] { return echo.closed() == 1; }));
  const double server_ms = ms_since(t0);
  std::cout << "cut seen by client after " << client_ms << " ms, by server after " << server_ms << " ms\n";
  EXPECT_LT(client_ms, 1000);
  EXPECT_LT(server_ms, 1000);
  EXPECT_TRUE(log.contains("conn 1 closed (cut) up 3 B down 3 B"));

  Sock again(r->port());
  EXPECT_EQ(echo_through(again, {4}, 0), Bytes{4});
}

TEST_F(Relay, WaitsForATargetThatStartsLater) {
  const uint16_t port = unused_port();
  ASSERT_NO_FATAL_FAILURE(start([](auto& o) { o.connect_timeout = 5000ms; }, port));
  Sock c(r->port());
  ASSERT_TRUE(c.send_all("hello"));
  std::this_thread::sleep_for(200ms);
  EchoServer late(port);
  EXPECT_EQ(c.recv_exact(5), Bytes({'h', 'e', 'l', 'l', 'o'}));
}

TEST_F(Relay, UnreachableTargetClosesTheClient) {
  ASSERT_NO_FATAL_FAILURE(start([](auto& o) { o.connect_timeout = 300ms; }, unused_port()));
  Sock c(r->port());
  const auto t0 = Clock::now();
  EXPECT_TRUE(c.sees_close());
  const double ms = ms_since(t0);
  EXPECT_GE(ms, 200);  // retried for about connect_timeout
  EXPECT_LT(ms, 2000);
  EXPECT_TRUE(log.contains("conn 1 closed (target unreachable: Connection refused)"));
}

// ---------------------------------------------------------------------------------------------
// The link_relay binary

occtest::Outcome run_relay(std::vector<std::string> args, const std::string& name) {
  args.insert(args.begin(), occtest::bin("link_relay"));
  return occtest::run_to_end(args, occtest::fresh_dir("relay_cli") / (name + ".log"), 10s);
}

TEST(LinkRelayCli, BadFlagsGiveOneErrorLineNamingTheFlag) {
  const std::vector<std::pair<std::vector<std::string>, std::string>> cases = {
      {{}, "--target"},
      {{"--target", "127.0.0.1"}, "--target"},
      {{"--target", "127.0.0.1:0"}, "--target"},
      {{"--target", "127.0.0.1:99999"}, "--target"},
      {{"--target", "127.0.0.1:1", "--listen", "nowhere"}, "--listen"},
      {{"--target", "127.0.0.1:1", "--delay-ms", "-5"}, "--delay-ms"},
      {{"--target", "127.0.0.1:1", "--rate-mbit", "fast"}, "--rate-mbit"},
      {{"--target", "127.0.0.1:1", "--up-jitter-ms", "-2"}, "--up-jitter-ms"},
      {{"--target", "127.0.0.1:1", "--seed"}, "--seed"},
      {{"--target", "127.0.0.1:1", "--bogus", "1"}, "--bogus"},
  };
  int i = 0;
  for (const auto& [args, flag] : cases) {
    SCOPED_TRACE(flag);
    occtest::expect_one_error(run_relay(args, "bad" + std::to_string(i++)), {flag}, {.code = 2, .whole_log = true});
  }
  const occtest::Outcome help = run_relay({"--help"}, "help");
  EXPECT_EQ(help.code, 0);
  for (const char* flag : {"--listen", "--port-file", "--target", "--delay-ms", "--jitter-ms", "--rate-mbit",
                           "--up-delay-ms", "--down-rate-mbit", "--control-port-file", "--seed", "--timeout-ms"})
    EXPECT_NE(help.log.find(flag), std::string::npos) << flag;
}

TEST(LinkRelayCli, RelaysWithPortFilesAndControlPort) {
  EchoServer echo;
  const auto dir = occtest::fresh_dir("relay_run");
  occtest::Proc p({occtest::bin("link_relay"), "--target", "127.0.0.1:" + std::to_string(echo.port()), "--port-file",
                   (dir / "port").string(), "--control-port-file", (dir / "control").string(), "--delay-ms", "10",
                   "--up-delay-ms", "5"},
                  dir / "relay.log");
  const int port = occtest::wait_port(dir / "port", p, 10s);
  const int control = occtest::wait_port(dir / "control", p, 10s);
  ASSERT_GT(port, 0) << p.log();
  ASSERT_GT(control, 0) << p.log();
  Sock c{uint16_t(port)}, ctl{uint16_t(control)};
  const auto t0 = Clock::now();
  EXPECT_EQ(echo_through(c, {1, 2, 3, 4}, 0), (Bytes{1, 2, 3, 4}));
  const double rtt = ms_since(t0);
  std::cout << "link_relay up 5 ms, down 10 ms: round trip " << rtt << " ms\n";
  EXPECT_GE(rtt, 15.0);
  EXPECT_LT(rtt, 75.0);
  ASSERT_TRUE(ctl.send_all("stats\n"));
  const std::string st = ctl.line();
  EXPECT_EQ(stat(st, "up"), 4u) << st;
  EXPECT_EQ(stat(st, "down"), 4u) << st;
  c.shutdown_write();
  EXPECT_TRUE(c.sees_close());
  EXPECT_TRUE(eventually([&] { return p.log().find("conn 1 closed (eof) up 4 B down 4 B") != std::string::npos; }))
      << p.log();
  EXPECT_NE(p.log().find("conn 1 open 127.0.0.1:"), std::string::npos) << p.log();
}

}  // namespace
