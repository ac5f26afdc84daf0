// TLS links of a keyed cluster (protocol/net/tls.hpp) over loopback, through a recording TCP
// proxy: messages arrive both ways and the wire shows none of their bytes; a wrong key, a key on
// one side only and a stranger are refused before any message; a byte altered on the way ends the
// link with an integrity error. 127.0.0.1 and port 0 only.
#include <algorithm>
#include <array>
#include <chrono>
#include <condition_variable>
#include <cstring>
#include <functional>
#include <mutex>
#include <optional>
#include <thread>
#include <utility>  // before asio: Boost 1.74 awaitable.hpp lacks it under C++20

#include <boost/asio.hpp>
#include <boost/asio/ssl.hpp>
#include <gtest/gtest.h>

#include "protocol/net/auth.hpp"
#include "protocol/net/transport.hpp"
#include "net_test_util.hpp"

using namespace occ;
using namespace occtest;
using namespace std::chrono_literals;
using net::Millis;
using Status = net::Received::Status;
namespace asio = boost::asio;
using tcp = asio::ip::tcp;

namespace {

constexpr uint64_t kFingerprint = 0x5eed0ff1ce0fca75;
const std::string kName = "tls-test-hello";

wire::Hello make_hello(wire::Role role) {
  wire::Hello h;
  h.role = role;
  h.viewport_width_px = 640;
  h.viewport_height_px = 480;
  h.scene_fingerprint = kFingerprint;
  h.arity = 8;
  h.leaf_items = 1;
  h.cluster_triangles = 2048;
  h.config_hash = 0xc0f;
  h.name = kName;
  return h;
}

net::ClusterKey key_of(char fill) { return *net::ClusterKey::from_bytes(std::string(40, fill)); }

bool contains_bytes(const std::vector<uint8_t>& hay, const std::vector<uint8_t>& needle) {
  return std::search(hay.begin(), hay.end(), needle.begin(), needle.end()) != hay.end();
}
template <class T>
std::vector<uint8_t> bytes_of(const T& v) {  // little-endian, as on the wire
  std::vector<uint8_t> b(sizeof v);
  std::memcpy(b.data(), &v, sizeof v);
  return b;
}
std::vector<uint8_t> bytes_of(const std::string& s) { return {s.begin(), s.end()}; }

// What no byte stream between members may show: the wire magic, the scene fingerprint, the
// hello's name, the marker ids of the test's NodeDiff, the marker text of its Bye.
const uint32_t kMarkerId = 0x7e57da7a;
const std::string kMarkerText = "marker-text-in-the-bye";
std::vector<std::vector<uint8_t>> secrets() {
  return {bytes_of(wire::kMagic), bytes_of(kFingerprint), bytes_of(kName), bytes_of(kMarkerId), bytes_of(kMarkerText)};
}

// One TCP connection from port() to the target, forwarded both ways and recorded. flip_next(up)
// makes the proxy invert one byte in the middle of the next chunk it reads in that direction
// (up: connector -> acceptor).
class Proxy {
 public:
  explicit Proxy(uint16_t target) : acceptor_(io_, {asio::ip::make_address("127.0.0.1"), 0}) {
    thread_ = std::thread([this, target] {
      boost::system::error_code ec;
      acceptor_.accept(client_, ec);
      if (!ec) server_.connect({asio::ip::make_address("127.0.0.1"), target}, ec);
      if (ec) return;
      std::thread up([this] { pump(client_, server_, 0); });
      pump(server_, client_, 1);
      up.join();
    });
  }
  ~Proxy() {
    boost::system::error_code ignored;
    acceptor_.close(ignored);
    client_.shutdown(tcp::socket::shutdown_both, ignored);
    server_.shutdown(tcp::socket::shutdown_both, ignored);
    thread_.join();
  }
  uint16_t port() const { return acceptor_.local_endpoint().port(); }
  void flip_next(bool up) {
    std::lock_guard lk(m_);
    flip_[up ? 0 : 1] = true;
  }
  // Waits until both directions ended (bounded), then returns what went up and down.
  std::pair<std::vector<uint8_t>, std::vector<uint8_t>> recorded(Millis timeout = 10s) {
    std::unique_lock lk(m_);
    cv_.wait_for(lk, timeout, [&] { return ended_ == 2; });
    return {seen_[0], seen_[1]};
  }

 private:
  void pump(tcp::socket& from, tcp::socket& to, int dir) {
    std::array<uint8_t, 65536> buf;
    boost::system::error_code ec;
    for (;;) {
      const size_t n = from.read_some(asio::buffer(buf), ec);
      if (ec) break;
      {
        std::lock_guard lk(m_);
        if (flip_[dir]) buf[n / 2] ^= 0x01, flip_[dir] = false;
        seen_[dir].insert(seen_[dir].end(), buf.begin(), buf.begin() + n);
      }
      asio::write(to, asio::buffer(buf.data(), n), ec);
      if (ec) break;
    }
    to.shutdown(tcp::socket::shutdown_send, ec);
    std::lock_guard lk(m_);
    ++ended_;
    cv_.notify_all();
  }

  asio::io_context io_;
  tcp::acceptor acceptor_;
  tcp::socket client_{io_}, server_{io_};
  std::mutex m_;
  std::condition_variable cv_;
  bool flip_[2] = {false, false};
  std::vector<uint8_t> seen_[2];
  int ended_ = 0;
  std::thread thread_;
};

net::PeerExpectation with_key(const net::ClusterKey* key) {
  net::PeerExpectation e;
  e.key = key;
  return e;
}

// A connector (render client) and an acceptor (switch node) handshake through `proxy`.
struct Pair {
  Result<wire::Hello> acceptor_hello = Error{"not run"}, connector_hello = Error{"not run"};
  std::optional<net::Connection> acceptor, connector;
};
Pair handshake_pair(net::Listener& listener, uint16_t connect_port, const net::ClusterKey* acceptor_key,
                    const net::ClusterKey* connector_key, LogCapture& log) {
  Pair p;
  std::thread server([&] {
    auto conn = listener.accept(5s, log.options(acceptor_key));
    if (!conn) return void(p.acceptor_hello = Error{conn.error()});
    p.acceptor_hello = net::handshake(*conn, make_hello(wire::Role::switch_node), with_key(acceptor_key), 5s);
    p.acceptor.emplace(std::move(*conn));
  });
  auto conn = net::Connection::connect("127.0.0.1", connect_port, 5s, log.options(connector_key));
  if (conn) {
    p.connector_hello = net::handshake(*conn, make_hello(wire::Role::render_client), with_key(connector_key), 5s);
    p.connector.emplace(std::move(*conn));
  }
  server.join();
  return p;
}

class Tls : public WithListener {};

// Both ways through a proxy; returns what went up and down. Checks the messages arrive intact.
std::pair<std::vector<uint8_t>, std::vector<uint8_t>> exchange(net::Listener& listener, const net::ClusterKey* key,
                                                               LogCapture& log, net::ConnectionStats* connector_stats) {
  Proxy proxy(listener.port());
  Pair p = handshake_pair(listener, proxy.port(), key, key, log);
  EXPECT_TRUE(p.acceptor_hello) << p.acceptor_hello.error();
  EXPECT_TRUE(p.connector_hello) << p.connector_hello.error();
  if (!p.acceptor_hello || !p.connector_hello) return {};
  EXPECT_EQ(p.connector->encrypted(), key != nullptr);
  EXPECT_EQ(p.acceptor->encrypted(), key != nullptr);
  const wire::NodeDiff diff{7, {kMarkerId, 1, 2, 3}, {kMarkerId + 1}};
  EXPECT_EQ(p.connector->send(diff), std::nullopt);
  net::Received r = p.acceptor->receive(5s);
  EXPECT_TRUE(r.ok()) << r.reason;
  EXPECT_EQ(std::get_if<wire::NodeDiff>(&r.message) ? *std::get_if<wire::NodeDiff>(&r.message) : wire::NodeDiff{}, diff);
  const wire::EndOfFrame eof{.frame = 7, .visible_count = kMarkerId, .set_hash = kFingerprint};
  EXPECT_EQ(p.acceptor->send(eof), std::nullopt);
  r = p.connector->receive(5s);
  EXPECT_TRUE(r.ok()) << r.reason;
  EXPECT_EQ(std::get_if<wire::EndOfFrame>(&r.message) ? *std::get_if<wire::EndOfFrame>(&r.message) : wire::EndOfFrame{},
            eof);
  p.connector->close(kMarkerText);
  r = p.acceptor->receive(5s);
  EXPECT_EQ(r.status, Status::closed);
  EXPECT_EQ(r.reason, "peer said bye: " + kMarkerText);
  p.acceptor->close("done");
  auto streams = proxy.recorded();
  *connector_stats = p.connector->stats();
  return streams;
}

}  // namespace

TEST_F(Tls, MessagesArriveBothWaysAndTheWireShowsNoneOfTheirBytes) {
  const net::ClusterKey key = key_of('k');
  net::ConnectionStats stats;
  const auto [up, down] = exchange(*listener, &key, log, &stats);
  ASSERT_FALSE(up.empty());
  ASSERT_FALSE(down.empty());
  for (const auto& s : secrets()) {
    EXPECT_FALSE(contains_bytes(up, s)) << "plaintext bytes on the wire, connector -> acceptor";
    EXPECT_FALSE(contains_bytes(down, s)) << "plaintext bytes on the wire, acceptor -> connector";
  }
  // The counters see the wire: what the proxy forwarded, more than the messages.
  EXPECT_EQ(stats.socket_bytes_sent, up.size());
  EXPECT_EQ(stats.socket_bytes_received, down.size());
  EXPECT_GT(stats.socket_bytes_sent, stats.sent.bytes);
  EXPECT_TRUE(log.snapshot().empty());

  // The control: the same exchange without a key shows every one of them (the test can see plaintext).
  const auto [plain_up, plain_down] = exchange(*listener, nullptr, log, &stats);
  std::vector<uint8_t> both = plain_up;
  both.insert(both.end(), plain_down.begin(), plain_down.end());
  for (const auto& s : secrets()) EXPECT_TRUE(contains_bytes(both, s));
  EXPECT_EQ(stats.socket_bytes_sent, stats.sent.bytes) << "plain TCP: the wire carries the messages only";
  EXPECT_EQ(stats.socket_bytes_sent, plain_up.size());
}

TEST_F(Tls, AWrongKeyIsRefusedOnBothSidesBeforeAnyMessage) {
  const net::ClusterKey key = key_of('k'), wrong = key_of('w');
  Pair p = handshake_pair(*listener, listener->port(), &key, &wrong, log);
  ASSERT_FALSE(p.acceptor_hello);
  ASSERT_FALSE(p.connector_hello);
  EXPECT_TRUE(contains(p.acceptor_hello.error(), "TLS handshake failed: cluster key mismatch")) << p.acceptor_hello.error();
  EXPECT_TRUE(contains(p.connector_hello.error(), "TLS handshake failed: cluster key mismatch")) << p.connector_hello.error();
  EXPECT_EQ(p.acceptor->stats().received.messages, 0u);
  EXPECT_EQ(p.connector->stats().received.messages, 0u);
  const auto lines = log.snapshot();
  ASSERT_EQ(lines.size(), 2u) << "one line per side";
  for (const auto& l : lines) EXPECT_TRUE(contains(l, "occ_net: peer 127.0.0.1:")) << l;
}

TEST_F(Tls, AKeyOnOneSideOnlyIsRefusedOnBothSidesSayingWhichHasIt) {
  const net::ClusterKey key = key_of('k');
  Pair a = handshake_pair(*listener, listener->port(), &key, nullptr, log);  // a client without the key
  ASSERT_FALSE(a.acceptor_hello);
  ASSERT_FALSE(a.connector_hello);
  EXPECT_TRUE(contains(a.acceptor_hello.error(), "TLS handshake failed: the peer speaks no TLS: it has no cluster key"))
      << a.acceptor_hello.error();
  EXPECT_TRUE(contains(a.connector_hello.error(), "the peer speaks TLS: it has a cluster key (--cluster-key-file), this process has none"))
      << a.connector_hello.error();
  EXPECT_EQ(a.connector->stats().received.messages, 0u) << "the keyed node said nothing in the clear";

  Pair b = handshake_pair(*listener, listener->port(), nullptr, &key, log);  // a keyed client, a node without
  ASSERT_FALSE(b.acceptor_hello);
  ASSERT_FALSE(b.connector_hello);
  EXPECT_TRUE(contains(b.acceptor_hello.error(), "the peer speaks TLS: it has a cluster key (--cluster-key-file), this process has none"))
      << b.acceptor_hello.error();
  EXPECT_TRUE(contains(b.connector_hello.error(), "TLS handshake failed: the peer speaks no TLS: it has no cluster key"))
      << b.connector_hello.error();
}

TEST_F(Tls, AStrangerWithoutTheKeyLearnsNothingButARefusal) {
  const net::ClusterKey key = key_of('k');
  Result<net::Peer> accepted = Error{"not run"};
  std::thread node([&] {
    accepted = listener->accept_peer(make_hello(wire::Role::switch_node), with_key(&key), 4s, 2s, log.options(&key));
  });
  std::vector<std::vector<uint8_t>> heard;
  {  // speaks the wire protocol in the clear, as a keyless member would
    asio::io_context io;
    tcp::socket s(io);
    s.connect({asio::ip::make_address("127.0.0.1"), listener->port()});
    asio::write(s, asio::buffer(wire::encode(make_hello(wire::Role::render_client))));
    std::vector<uint8_t> got;
    boost::system::error_code ec;
    asio::read(s, asio::dynamic_buffer(got), ec);  // until the node closes
    heard.push_back(got);
  }
  {  // speaks TLS 1.3, but has no PSK (and wants the node's certificate, which does not exist)
    asio::io_context io;
    asio::ssl::context ctx(asio::ssl::context::tls_client);
    asio::ssl::stream<tcp::socket> s(io, ctx);
    s.next_layer().connect({asio::ip::make_address("127.0.0.1"), listener->port()});
    boost::system::error_code ec;
    s.handshake(asio::ssl::stream_base::client, ec);
    EXPECT_TRUE(ec) << "the TLS handshake must fail without the key";
    std::vector<uint8_t> got;
    asio::read(s.next_layer(), asio::dynamic_buffer(got), ec);
    heard.push_back(got);
  }
  node.join();
  ASSERT_FALSE(accepted);
  EXPECT_EQ(accepted.error_kind(), ErrorKind::timeout);
  EXPECT_EQ(listener->rejected(), 2u);
  for (const auto& got : heard) {
    EXPECT_LT(got.size(), 64u) << "a refusal (a TLS alert at most), nothing more";
    for (const auto& s : secrets()) EXPECT_FALSE(contains_bytes(got, s));
  }
  const auto lines = log.snapshot();
  ASSERT_EQ(lines.size(), 2u);
  EXPECT_TRUE(contains(lines[0], "TLS handshake failed: the peer speaks no TLS")) << lines[0];
  EXPECT_TRUE(contains(lines[1], "TLS handshake failed: the peer offered no cluster-key PSK")) << lines[1];
}

TEST_F(Tls, AByteAlteredOnTheWayEndsTheLinkWithAnIntegrityError) {
  const net::ClusterKey key = key_of('k');
  for (bool up : {true, false}) {
    SCOPED_TRACE(up ? "connector -> acceptor" : "acceptor -> connector");
    Proxy proxy(listener->port());
    Pair p = handshake_pair(*listener, proxy.port(), &key, &key, log);
    ASSERT_TRUE(p.acceptor_hello) << p.acceptor_hello.error();
    ASSERT_TRUE(p.connector_hello) << p.connector_hello.error();
    const size_t lines_before = log.snapshot().size();
    proxy.flip_next(up);
    net::Connection& sender = up ? *p.connector : *p.acceptor;
    net::Connection& receiver = up ? *p.acceptor : *p.connector;
    EXPECT_EQ(sender.send(wire::NodeDiff{9, {kMarkerId}, {}}), std::nullopt);
    const net::Received r = receiver.receive(5s);
    EXPECT_EQ(r.status, Status::error) << "no message may come out of an altered record";
    EXPECT_TRUE(contains(r.reason, "TLS integrity check failed: a record was altered on the way")) << r.reason;
    EXPECT_EQ(receiver.stats().errors, 1u);
    const net::Received s = sender.receive(5s);  // the sender's link ends too, without a message
    EXPECT_EQ(s.status, Status::error) << s.reason;
    const auto lines = log.snapshot();
    ASSERT_GE(lines.size(), lines_before + 1);
    EXPECT_TRUE(contains(lines[lines_before], "occ_net: peer 127.0.0.1:")) << lines[lines_before];
  }
}

TEST_F(Tls, LargeAndSmallMessagesInBurstsArriveIntactAndInOrder) {
  // Messages larger than a TLS record (16 KiB) and bursts of small ones coalesced into one record.
  const net::ClusterKey key = key_of('k');
  Pair p = handshake_pair(*listener, listener->port(), &key, &key, log);
  ASSERT_TRUE(p.acceptor_hello) << p.acceptor_hello.error();
  ASSERT_TRUE(p.connector_hello) << p.connector_hello.error();
  std::vector<wire::NodeDiff> sent;
  for (uint32_t i = 0; i < 300; ++i) {
    wire::NodeDiff d{i, {}, {}};
    const uint32_t n = i % 10 == 0 ? 30000 + i : i % 7;  // 120 KB every tenth, else a few bytes
    for (uint32_t k = 0; k < n; ++k) d.added.push_back(k * 3 + i);
    sent.push_back(std::move(d));
  }
  std::thread sender([&] {
    for (const auto& d : sent) EXPECT_EQ(p.connector->send(d), std::nullopt);
  });
  size_t got = 0;
  for (; got < sent.size(); ++got) {
    const net::Received r = p.acceptor->receive(10s);
    ASSERT_TRUE(r.ok()) << r.reason;
    const auto* d = std::get_if<wire::NodeDiff>(&r.message);
    ASSERT_TRUE(d);
    ASSERT_EQ(*d, sent[got]) << "message " << got;
  }
  sender.join();
  const net::ConnectionStats s = p.connector->stats();
  EXPECT_GT(s.socket_bytes_sent, s.sent.bytes);
  EXPECT_LT(s.socket_bytes_sent, s.sent.bytes + s.sent.bytes / 50 + 4096) << "TLS adds a little per record";
  EXPECT_TRUE(log.snapshot().empty());
}

// Messages queued while the TLS handshake ends are written once: the handshake's completion and
// a write the owner queued meanwhile both started one, and the second wrote the first's bytes
// again (a switch node once read a render client's hello twice: "expected proof, got hello").
// The connector's first send comes up to 3 ms after it connected (across the connections), so that
// some land as the handshake ends; each acceptor must receive exactly frames 0..n-1, in order,
// then the connector's Bye. The window is a few instructions wide: with the handshake's
// completion slowed by hand (a sleep put there) the old code failed here (messages arrived
// twice); as it is, this passes on the old code too and guards the fix under load.
TEST_F(Tls, MessagesQueuedWhileTheHandshakeEndsArriveOnce) {
  const net::ClusterKey key = key_of('k');
  constexpr uint32_t kConnections = 60, kMessages = 120;
  for (uint32_t c = 0; c < kConnections; ++c) {
    std::vector<uint32_t> frames;
    std::string end;
    std::thread server([&] {
      auto conn = listener->accept(5s, log.options(&key));
      if (!conn) return void(end = conn.error());
      for (;;) {
        net::Received r = conn->receive(5s);
        if (!r.ok()) return void(end = r.reason);
        if (const auto* d = std::get_if<wire::NodeDiff>(&r.message)) frames.push_back(d->frame);
      }
    });
    auto conn = net::Connection::connect("127.0.0.1", listener->port(), 5s, log.options(&key));
    ASSERT_TRUE(conn) << conn.error();
    std::this_thread::sleep_for(std::chrono::microseconds(50 * c));  // the first send, up to 3 ms in
    for (uint32_t f = 0; f < kMessages; ++f) {
      ASSERT_EQ(conn->send(wire::NodeDiff{f, {f}, {}}), std::nullopt);
      std::this_thread::sleep_for(std::chrono::microseconds(20));
    }
    conn->close("done");
    server.join();
    EXPECT_EQ(end, "peer said bye: done") << "connection " << c;
    ASSERT_EQ(frames.size(), kMessages) << "connection " << c;
    for (uint32_t f = 0; f < kMessages; ++f) ASSERT_EQ(frames[f], f) << "connection " << c;
  }
}
