// Loopback transport: handshake, a long diff stream, and misbehaving peers (garbage, disconnect
// mid-message, wrong fingerprint or version, silence, not reading). Every failure must end with
// the expected error within its timeout. 127.0.0.1 and port 0 only.
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <optional>
#include <random>
#include <thread>
#include <utility>  // before asio: Boost 1.74 awaitable.hpp lacks it under C++20

#include <boost/asio.hpp>
#include <gtest/gtest.h>

#include "protocol/net/auth.hpp"
#include "protocol/net/transport.hpp"
#include "net_test_util.hpp"
#include "protocol/visible_set.hpp"

using namespace occ;
using namespace occtest;
using namespace std::chrono_literals;
using net::Millis;
using Status = net::Received::Status;
using Clock = std::chrono::steady_clock;
namespace asio = boost::asio;

namespace {

wire::Hello make_hello(wire::Role role, uint8_t node_id = 0, uint64_t fingerprint = 0xf1f1) {
  wire::Hello h;
  h.role = role;
  h.node_id = node_id;
  h.viewport_width_px = 640;
  h.viewport_height_px = 480;
  h.scene_fingerprint = fingerprint;
  h.arity = 8;
  h.leaf_items = 1;
  h.cluster_triangles = 2048;
  h.config_hash = 0xc0f;
  h.name = "test";
  return h;
}


// "Returns when its timeout runs out, not long after": the bound catches a timeout taken in the
// wrong unit or never armed (a hang is ctest's --timeout), not speed. It is far above the timeouts
// (at most 600 ms) so that a loaded 2-core machine under TSan never trips it.
constexpr double kPromptMs = 20000;

double elapsed_ms(Clock::time_point since) {
  return std::chrono::duration<double, std::milli>(Clock::now() - since).count();
}

// A hand-driven peer on a plain blocking socket that can send arbitrary bytes.
struct RawPeer {
  asio::io_context io;
  asio::ip::tcp::socket sock{io};
  explicit RawPeer(uint16_t port) {
    sock.connect({asio::ip::make_address("127.0.0.1"), port});
  }
  void send(const std::vector<uint8_t>& bytes) { asio::write(sock, asio::buffer(bytes)); }
  // Reads frames until EOF or error; returns the decoded messages (stops at a bad frame).
  std::vector<wire::Message> read_all() {
    std::vector<uint8_t> data;
    boost::system::error_code ec;
    asio::read(sock, asio::dynamic_buffer(data), ec);
    std::vector<wire::Message> out;
    for (size_t pos = 0; pos + wire::kHeaderBytes <= data.size();) {
      auto h = wire::decode_header(std::span(data).subspan(pos));
      if (!h || pos + wire::kHeaderBytes + h->payload_bytes > data.size()) break;
      auto m = wire::decode(std::span(data).subspan(pos, wire::kHeaderBytes + h->payload_bytes));
      if (!m) break;
      out.push_back(*m);
      pos += wire::kHeaderBytes + h->payload_bytes;
    }
    return out;
  }
};

std::string bye_reason(const std::vector<wire::Message>& msgs) {
  for (const auto& m : msgs)
    if (auto* b = std::get_if<wire::Bye>(&m)) return b->reason;
  return "<no bye>";
}

// A port that was free a moment ago (for the tests that need a port before anyone listens).
uint16_t recently_free_port() {
  auto l = net::Listener::open(0);
  EXPECT_TRUE(l) << l.error();
  return l->port();
}

class Loopback : public WithListener {};
class Handshake : public WithListener {};
class Connection : public WithListener {};
class Listener : public WithListener {};

}  // namespace

TEST_F(Loopback, HelloThenTenThousandDiffsAndEndOfFramesArriveIntact) {
  constexpr uint32_t kIdLimit = 50000, kFrames = 100, kChangesPerFrame = 10000;

  std::string receiver_error;
  size_t diffs = 0, eofs = 0;
  net::ConnectionStats receiver_stats;
  std::thread receiver([&] {
    auto peer = listener->accept_peer(make_hello(wire::Role::render_client), {}, 10s);
    if (!peer) return void(receiver_error = peer.error());
    EXPECT_EQ(peer->hello.role, wire::Role::switch_node);
    EXPECT_EQ(peer->hello.name, "test");
    VisibleSet v(kIdLimit);
    DiffReceiver rx;
    for (;;) {
      net::Received r = peer->connection.receive(10s);
      if (r.status == Status::closed) {
        EXPECT_EQ(r.reason, "peer said bye: stream complete");
        break;
      }
      if (!r.ok()) return void(receiver_error = "receive: " + r.reason);
      std::optional<std::string> e;
      if (auto* d = std::get_if<wire::NodeDiff>(&r.message)) {
        ++diffs;
        e = rx.on_diff(v, *d);
      } else if (auto* eof = std::get_if<wire::EndOfFrame>(&r.message)) {
        ++eofs;
        e = rx.on_end_of_frame(v, *eof);
      }
      if (e) return void(receiver_error = *e);
    }
    receiver_stats = peer->connection.stats();
  });

  auto conn = net::Connection::connect("127.0.0.1", listener->port(), 5s);
  ASSERT_TRUE(conn) << conn.error();
  auto hello = net::handshake(*conn, make_hello(wire::Role::switch_node), {}, 5s);
  ASSERT_TRUE(hello) << hello.error();
  EXPECT_EQ(hello->role, wire::Role::render_client);

  std::mt19937_64 rng(3);
  VisibleSet cur(kIdLimit);
  for (uint32_t f = 1; f <= kFrames; ++f) {
    VisibleSet next = cur;
    // Exactly kChangesPerFrame changes: remove half of the set (or what is there), add the rest.
    std::vector<uint32_t> ids(cur.ids().begin(), cur.ids().end());
    std::shuffle(ids.begin(), ids.end(), rng);
    const size_t removals = std::min<size_t>(ids.size(), kChangesPerFrame / 2);
    for (size_t i = 0; i < removals; ++i) next.erase(ids[i]);
    while (next.size() < cur.size() - removals + (kChangesPerFrame - removals)) {
      const uint32_t id = static_cast<uint32_t>(rng() % kIdLimit);
      if (!cur.contains(id)) next.insert(id);
    }
    const SetDiff d = diff_sets(cur, next);
    ASSERT_EQ(d.added.size() + d.removed.size(), kChangesPerFrame);
    for (const auto& chunk : wire::chunk_node_diff(f, d.added, d.removed, 100))
      ASSERT_FALSE(conn->send(chunk));
    ASSERT_FALSE(conn->send(make_end_of_frame(f, d, next)));
    cur = std::move(next);
  }
  conn->close("stream complete");
  receiver.join();
  ASSERT_EQ(receiver_error, "");
  EXPECT_EQ(diffs, 10000u);
  EXPECT_EQ(eofs, kFrames);

  const auto sent = conn->stats().sent;
  const auto& got = receiver_stats.received;
  EXPECT_EQ(sent.messages_of(wire::Type::node_diff), 10000u);
  EXPECT_EQ(got.messages_of(wire::Type::node_diff), 10000u);
  EXPECT_EQ(got.bytes_of(wire::Type::node_diff), 10000u * (6 + 12 + 400));
  EXPECT_EQ(sent.bytes, got.bytes);  // hello + diffs + eofs + bye
  EXPECT_EQ(sent.messages, 1 + 10000 + kFrames + 1);
  EXPECT_EQ(got.bytes_of(wire::Type::hello) + got.bytes_of(wire::Type::node_diff) +
                got.bytes_of(wire::Type::end_of_frame) + got.bytes_of(wire::Type::bye),
            got.bytes);
  EXPECT_EQ(conn->stats().errors, 0u);
  EXPECT_EQ(receiver_stats.errors, 0u);
}

TEST_F(Loopback, StrangersAreRejectedWhileTheListenerWaitsForItsPeer) {
  const auto mine = make_hello(wire::Role::switch_node, 0);
  Result<net::Peer> accepted = Error{"not run"};
  std::thread server([&] {
    accepted = listener->accept_peer(mine, {wire::Role::switch_node, 1}, 10s, 300ms,
                                     log.options());
  });

  // 1: garbage.
  std::vector<wire::Message> garbage_saw;
  {
    RawPeer garbage(listener->port());
    garbage.send({0x42, 0x42, 1, 2, 3, 4, 5, 6, 7, 8});
    garbage_saw = garbage.read_all();
  }
  // 2: silence (no hello within 300 ms).
  std::vector<wire::Message> silent_saw;
  {
    RawPeer silent(listener->port());
    silent_saw = silent.read_all();  // returns when the listener gives up on it
  }
  // 3: a well-formed hello for another scene.
  {
    auto wrong = net::Connection::connect("127.0.0.1", listener->port(), 2s, log.options());
    ASSERT_TRUE(wrong) << wrong.error();
    auto h = net::handshake(*wrong, make_hello(wire::Role::switch_node, 1, 0xbad), {}, 2s);
    EXPECT_FALSE(h);
  }
  // 4: the expected peer.
  auto good = net::Connection::connect("127.0.0.1", listener->port(), 2s);
  ASSERT_TRUE(good) << good.error();
  auto h = net::handshake(*good, make_hello(wire::Role::switch_node, 1), {}, 2s);
  server.join();
  ASSERT_TRUE(h) << h.error();
  ASSERT_TRUE(accepted) << accepted.error();
  EXPECT_EQ(accepted->hello.node_id, 1);
  EXPECT_EQ(listener->rejected(), 3u);

  // The strangers were told why before the listener closed on them.
  EXPECT_EQ(bye_reason(garbage_saw), "protocol error: unknown message type 16962");
  EXPECT_EQ(bye_reason(silent_saw), "no hello within 300 ms");

  // One line per rejected stranger on the listener side (plus one for the wrong-scene client's
  // own side), each naming the peer address and the reason.
  const auto lines = log.snapshot();
  ASSERT_EQ(lines.size(), 4u);
  for (const auto& line : lines) EXPECT_TRUE(contains(line, "occ_net: peer 127.0.0.1:")) << line;
  EXPECT_TRUE(contains(lines[0], "unknown message type 16962")) << lines[0];
  EXPECT_TRUE(contains(lines[1], "no hello within 300 ms")) << lines[1];
  size_t fingerprint_lines = 0;
  for (const auto& line : lines)
    fingerprint_lines += contains(line, "scene fingerprint mismatch: ours 0x");
  EXPECT_EQ(fingerprint_lines, 2u);
}

TEST_F(Loopback, ListenerGivesUpAfterTheOverallTimeoutNamingTheLastRejection) {
  Result<net::Peer> accepted = Error{"not run"};
  const auto t0 = Clock::now();
  std::thread server([&] {
    accepted = listener->accept_peer(make_hello(wire::Role::switch_node), {}, 600ms, 2s,
                                     log.options());
  });
  RawPeer garbage(listener->port());
  garbage.send({0xff, 0xff, 0, 0, 0, 0});
  server.join();
  EXPECT_LT(elapsed_ms(t0), kPromptMs);
  ASSERT_FALSE(accepted);
  EXPECT_TRUE(contains(accepted.error(), "no valid peer on 127.0.0.1:")) << accepted.error();
  EXPECT_EQ(accepted.error_kind(), ErrorKind::timeout) << "a kind to act on, not the text";
  EXPECT_TRUE(contains(accepted.error(), "within 600 ms (1 rejected; last: peer 127.0.0.1:"))
      << accepted.error();
  EXPECT_TRUE(contains(accepted.error(), "unknown message type 65535")) << accepted.error();
}

TEST_F(Loopback, PeerThatDisconnectsMidMessageEndsWithAnError) {
  std::thread peer([&] {
    RawPeer raw(listener->port());
    raw.send(wire::encode(make_hello(wire::Role::switch_node)));
    std::vector<uint8_t> their_hello(wire::encode(make_hello(wire::Role::render_client)).size());
    asio::read(raw.sock, asio::buffer(their_hello));  // nothing unread at close: FIN, not RST
    auto diff = wire::encode(wire::NodeDiff{1, {1, 2, 3, 4, 5}, {}});
    diff.resize(diff.size() - 7);
    raw.send(diff);
    std::this_thread::sleep_for(50ms);
  });  // closes the socket
  auto conn = listener->accept(5s, log.options());
  ASSERT_TRUE(conn) << conn.error();
  ASSERT_TRUE(net::handshake(*conn, make_hello(wire::Role::render_client), {}, 5s));
  const auto t0 = Clock::now();
  net::Received r = conn->receive(5s);
  peer.join();
  EXPECT_LT(elapsed_ms(t0), kPromptMs);
  EXPECT_EQ(r.status, Status::error);
  EXPECT_EQ(r.reason, "peer disconnected mid-message (25 of 32 node_diff payload bytes)");
  EXPECT_EQ(conn->stats().errors, 1u);
  ASSERT_EQ(log.snapshot().size(), 1u);
  EXPECT_TRUE(contains(log.snapshot()[0], r.reason));
  EXPECT_EQ(conn->receive(10ms).status, Status::error);  // stays ended
  EXPECT_TRUE(contains(conn->send(wire::Bye{"x"}).value_or(""), "connection ended"));
}

TEST_F(Loopback, PeerThatClosesWithoutByeEndsWithAnError) {
  std::thread peer([&] {
    RawPeer raw(listener->port());
    raw.send(wire::encode(wire::Camera{}));
  });
  auto conn = listener->accept(5s, log.options());
  ASSERT_TRUE(conn) << conn.error();
  peer.join();
  net::Received r = conn->receive(5s);
  ASSERT_EQ(r.status, Status::message);  // what arrived before the end is delivered first
  r = conn->receive(5s);
  EXPECT_EQ(r.status, Status::error);
  EXPECT_EQ(r.reason, "peer closed the connection without bye");
}

TEST_F(Handshake, WrongSceneFingerprintFailsOnBothSidesNamingBothValues) {
  LogCapture server_log, client_log;
  Result<wire::Hello> server_result = Error{"not run"};
  std::thread server([&] {
    auto conn = listener->accept(5s, server_log.options());
    ASSERT_TRUE(conn) << conn.error();
    server_result = net::handshake(
        *conn, make_hello(wire::Role::switch_node, 0, 0x1111222233334444ULL), {}, 5s);
  });
  auto conn = net::Connection::connect("127.0.0.1", listener->port(), 5s, client_log.options());
  ASSERT_TRUE(conn) << conn.error();
  const auto t0 = Clock::now();
  auto client_result = net::handshake(
      *conn, make_hello(wire::Role::render_client, 0, 0xaaaabbbbccccddddULL), {}, 5s);
  server.join();
  EXPECT_LT(elapsed_ms(t0), kPromptMs);
  ASSERT_FALSE(client_result);
  ASSERT_FALSE(server_result);
  EXPECT_TRUE(contains(client_result.error(),
                       "scene fingerprint mismatch: ours 0xaaaabbbbccccdddd, peer has "
                       "0x1111222233334444"))
      << client_result.error();
  EXPECT_TRUE(contains(server_result.error(),
                       "scene fingerprint mismatch: ours 0x1111222233334444, peer has "
                       "0xaaaabbbbccccdddd"))
      << server_result.error();
  EXPECT_TRUE(contains(client_result.error(), "peer 127.0.0.1:" + std::to_string(listener->port())))
      << client_result.error();
  EXPECT_EQ(server_log.snapshot().size(), 1u);
  EXPECT_EQ(client_log.snapshot().size(), 1u);
  EXPECT_FALSE(conn->is_open());
}

TEST_F(Handshake, WrongProtocolVersionIsRefusedNamingBothVersions) {
  std::vector<wire::Message> peer_saw;
  std::thread peer([&] {
    RawPeer raw(listener->port());
    auto hello = wire::encode(make_hello(wire::Role::switch_node));
    hello[6 + 4] = 1;  // version field: the version before this build's
    raw.send(hello);
    peer_saw = raw.read_all();
  });
  auto conn = listener->accept(5s, log.options());
  ASSERT_TRUE(conn) << conn.error();
  auto result = net::handshake(*conn, make_hello(wire::Role::render_client), {}, 5s);
  peer.join();
  ASSERT_FALSE(result);
  EXPECT_TRUE(contains(result.error(),
                       "hello: unsupported protocol version 1 (this build speaks 9)"))
      << result.error();
  EXPECT_EQ(bye_reason(peer_saw),
            "protocol error: hello: unsupported protocol version 1 (this build speaks 9)");
  EXPECT_EQ(log.snapshot().size(), 1u);
}

TEST_F(Handshake, UnexpectedRoleIsRefusedAndThePeerIsToldWhy) {
  Result<wire::Hello> server_result = Error{"not run"};
  std::thread server([&] {
    auto conn = listener->accept(5s, log.options());
    ASSERT_TRUE(conn) << conn.error();
    server_result = net::handshake(*conn, make_hello(wire::Role::switch_node),
                                   {wire::Role::switch_node, std::nullopt}, 5s);
  });
  auto conn = net::Connection::connect("127.0.0.1", listener->port(), 5s, log.options());
  ASSERT_TRUE(conn) << conn.error();
  auto client_result = net::handshake(*conn, make_hello(wire::Role::render_client), {}, 5s);
  server.join();
  ASSERT_TRUE(client_result) << client_result.error();  // the client accepts any role
  ASSERT_FALSE(server_result);
  EXPECT_TRUE(contains(server_result.error(),
                       "unexpected role render_client (expected switch_node)"));
  const net::Received r = conn->receive(5s);
  EXPECT_EQ(r.status, Status::closed);
  EXPECT_EQ(r.reason, "peer said bye: unexpected role render_client (expected switch_node)");
}

TEST_F(Handshake, SilentPeerTimesOut) {
  RawPeer silent(listener->port());
  auto conn = listener->accept(5s, log.options());
  ASSERT_TRUE(conn) << conn.error();
  const auto t0 = Clock::now();
  auto result = net::handshake(*conn, make_hello(wire::Role::switch_node), {}, 300ms);
  const double ms = elapsed_ms(t0);
  EXPECT_GE(ms, 290);
  EXPECT_LT(ms, kPromptMs);
  ASSERT_FALSE(result);
  EXPECT_TRUE(contains(result.error(), "no hello within 300 ms")) << result.error();
}

TEST_F(Handshake, ListenerThatNeverAnswersTimesOutOnTheConnectingSide) {
  // The kernel completes the TCP handshake from the backlog, but nobody ever reads or writes.
  auto conn = net::Connection::connect("127.0.0.1", listener->port(), 2s, log.options());
  ASSERT_TRUE(conn) << conn.error();
  const auto t0 = Clock::now();
  auto result = net::handshake(*conn, make_hello(wire::Role::render_client), {}, 300ms);
  EXPECT_LT(elapsed_ms(t0), kPromptMs);
  ASSERT_FALSE(result);
  EXPECT_TRUE(contains(result.error(), "no hello within 300 ms")) << result.error();
}

TEST(Connect, RetriesUntilThePeerListens) {
  const uint16_t port = recently_free_port();
  std::thread late_server([&] {
    std::this_thread::sleep_for(300ms);
    auto listener = net::Listener::open(port);
    ASSERT_TRUE(listener) << listener.error();
    auto peer = listener->accept_peer(make_hello(wire::Role::switch_node), {}, 5s);
    ASSERT_TRUE(peer) << peer.error();
    EXPECT_EQ(peer->connection.receive(5s).status, Status::closed);
  });
  const auto t0 = Clock::now();
  auto conn = net::Connection::connect("127.0.0.1", port, 5s);
  ASSERT_TRUE(conn) << conn.error();
  EXPECT_GE(elapsed_ms(t0), 250);
  ASSERT_TRUE(net::handshake(*conn, make_hello(wire::Role::render_client), {}, 5s));
  conn->close("done");
  late_server.join();
}

TEST(Connect, GivesUpAfterTheRetryTimeout) {
  const uint16_t port = recently_free_port();
  const auto t0 = Clock::now();
  auto conn = net::Connection::connect("127.0.0.1", port, 300ms);
  const double ms = elapsed_ms(t0);
  ASSERT_FALSE(conn);
  EXPECT_GE(ms, 290);
  EXPECT_LT(ms, kPromptMs);
  EXPECT_TRUE(contains(conn.error(), "cannot connect to 127.0.0.1:" + std::to_string(port) +
                                         " within 300 ms: Connection refused"))
      << conn.error();
}

TEST_F(Connection, OversizedLengthIsRejectedBeforeAnyPayloadIsRead) {
  RawPeer raw(listener->port());
  raw.send({3, 0, 0xff, 0xff, 0xff, 0x7f});  // node_diff, 2 GiB
  auto conn = listener->accept(5s, log.options());
  ASSERT_TRUE(conn) << conn.error();
  const net::Received r = conn->receive(5s);
  EXPECT_EQ(r.status, Status::error);
  EXPECT_EQ(r.reason, "node_diff payload too large: 2147483647 bytes (maximum 1048576)");
  EXPECT_EQ(bye_reason(raw.read_all()), "protocol error: " + r.reason);
}

TEST_F(Connection, SendFailsWithinTheTimeoutWhenThePeerStopsReading) {
  RawPeer raw(listener->port());  // never reads
  auto options = log.options();
  options.max_send_queue_bytes = 256 << 10;
  options.send_timeout = 300ms;
  auto conn = listener->accept(5s, options);
  ASSERT_TRUE(conn) << conn.error();
  wire::NodeDiff big{1, {}, {}};
  for (uint32_t i = 0; i < 60000; ++i) big.added.push_back(i);
  const auto t0 = Clock::now();
  std::optional<std::string> error;
  for (int i = 0; i < 2000 && !error; ++i) error = conn->send(big);  // at most ~480 MB
  ASSERT_TRUE(error);
  EXPECT_LT(elapsed_ms(t0), kPromptMs);
  EXPECT_TRUE(contains(*error, "send queue full for 300 ms")) << *error;
  EXPECT_TRUE(contains(*error, "peer is not reading")) << *error;
  EXPECT_EQ(conn->receive(10ms).status, Status::error);
  EXPECT_EQ(log.snapshot().size(), 1u);
}

TEST_F(Connection, InvalidMessagesAreRefusedLocally) {
  net::ConnectionOptions options;
  options.close_linger = 200ms;  // nobody accepts: the close waits out the linger
  auto conn = net::Connection::connect("127.0.0.1", listener->port(), 2s, options);
  ASSERT_TRUE(conn) << conn.error();
  wire::Camera bad;
  bad.near_dist = 0;
  EXPECT_EQ(conn->send(bad).value_or(""), "cannot send invalid message: camera: near 0 <= 0");
  EXPECT_TRUE(conn->is_open());
  EXPECT_EQ(conn->stats().sent.messages, 0u);
}

TEST_F(Connection, ConcurrentSendersInterleaveWholeMessages) {
  auto client = net::Connection::connect("127.0.0.1", listener->port(), 2s);
  ASSERT_TRUE(client) << client.error();
  auto server = listener->accept(2s);
  ASSERT_TRUE(server) << server.error();
  constexpr int kThreads = 4, kPerThread = 2000;
  std::vector<std::thread> senders;
  for (int t = 0; t < kThreads; ++t)
    senders.emplace_back([&, t] {
      for (uint32_t i = 0; i < kPerThread; ++i) {
        // Thread t owns ids t*1e6 + i; the camera frame encodes (thread, i) the same way.
        wire::Camera c;
        c.frame = t * 1000000u + i;
        const wire::Message m = i % 2 ? wire::Message{wire::NodeDiff{i, {c.frame}, {}}}
                                      : wire::Message{c};
        ASSERT_FALSE(client->send(m));
      }
    });
  std::vector<uint32_t> next(kThreads, 0);
  for (int n = 0; n < kThreads * kPerThread; ++n) {
    net::Received r = server->receive(5s);
    ASSERT_TRUE(r.ok()) << r.reason;
    uint32_t tag = 0;
    if (auto* d = std::get_if<wire::NodeDiff>(&r.message)) tag = d->added.at(0);
    else tag = std::get<wire::Camera>(r.message).frame;
    const uint32_t t = tag / 1000000, i = tag % 1000000;
    ASSERT_LT(t, static_cast<uint32_t>(kThreads));
    EXPECT_EQ(i, next[t]++) << "thread " << t << " out of order";
  }
  for (auto& s : senders) s.join();
  EXPECT_EQ(server->stats().received.messages, static_cast<uint64_t>(kThreads * kPerThread));
}

TEST_F(Connection, SlowReceiverPausesTheStreamWithoutLosingMessages) {
  net::ConnectionOptions small;
  small.max_receive_queue_bytes = 64 << 10;
  auto client = net::Connection::connect("127.0.0.1", listener->port(), 2s);
  ASSERT_TRUE(client) << client.error();
  auto server = listener->accept(2s, small);
  ASSERT_TRUE(server) << server.error();
  std::thread sender([&] {
    for (uint32_t f = 0; f < 10000; ++f) ASSERT_FALSE(client->send(wire::NodeDiff{f, {f}, {}}));
    client->close("done");
  });
  std::this_thread::sleep_for(200ms);  // let the inbox fill past its limit
  for (uint32_t f = 0; f < 10000; ++f) {
    net::Received r = server->receive(5s);
    ASSERT_TRUE(r.ok()) << r.reason;
    ASSERT_EQ(std::get<wire::NodeDiff>(r.message).frame, f);
  }
  EXPECT_EQ(server->receive(5s).status, Status::closed);
  sender.join();
}

TEST_F(Listener, BindsLoopbackByDefaultAndPublishesItsPortInAFile) {
  EXPECT_EQ(listener->address(), "127.0.0.1");
  EXPECT_NE(listener->port(), 0);

  const auto dir = std::filesystem::temp_directory_path() /
                   ("occ_net_test_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string file = (dir / "port").string();
  ASSERT_FALSE(net::write_port_file(file, listener->port()));
  auto port = net::read_port_file(file, 1s);
  ASSERT_TRUE(port) << port.error();
  EXPECT_EQ(*port, listener->port());
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir),
                          std::filesystem::directory_iterator{}), 1);  // no temp left

  const auto t0 = Clock::now();
  auto missing = net::read_port_file((dir / "missing").string(), 100ms);
  EXPECT_LT(elapsed_ms(t0), kPromptMs);
  ASSERT_FALSE(missing);
  EXPECT_TRUE(contains(missing.error(), "did not appear within 100 ms"));
  std::ofstream(dir / "junk") << "80x\n";
  EXPECT_FALSE(net::read_port_file((dir / "junk").string(), 100ms));
  std::filesystem::remove_all(dir);

  auto taken = net::Listener::open(listener->port());
  ASSERT_FALSE(taken);
  EXPECT_TRUE(contains(taken.error(), "cannot listen on 127.0.0.1:")) << taken.error();
  EXPECT_FALSE(net::Listener::open(0, "not-an-address"));
}

TEST_F(Listener, AcceptTimesOutWhenNobodyConnects) {
  const auto t0 = Clock::now();
  auto conn = listener->accept(200ms);
  EXPECT_GE(elapsed_ms(t0), 190);
  EXPECT_LT(elapsed_ms(t0), kPromptMs);
  ASSERT_FALSE(conn);
  EXPECT_TRUE(contains(conn.error(), "within 200 ms")) << conn.error();
}

// ---- The cluster key in the handshake (wire.hpp "Handshake", docs/security.md) ----

namespace {

net::ClusterKey key_of(char fill) { return *net::ClusterKey::from_bytes(std::string(40, fill)); }

struct Outcomes {
  Result<wire::Hello> acceptor = Error{"not run"}, connector = Error{"not run"};
  std::unique_ptr<net::Connection> connection;  // the connector's, after its handshake
};

// The acceptor's handshake (a switch node) in a thread, the connector's (a render client) here.
Outcomes handshake_both(net::Listener& listener, const net::PeerExpectation& acceptor,
                        const net::PeerExpectation& connector, LogCapture& log) {
  Outcomes o;
  std::thread server([&] {
    auto conn = listener.accept(5s, log.options(300ms, acceptor.key));
    if (!conn) return;
    o.acceptor = net::handshake(*conn, make_hello(wire::Role::switch_node), acceptor, 5s);
    if (o.acceptor) conn->receive(2s);  // until the client's Bye
  });
  auto conn = net::Connection::connect("127.0.0.1", listener.port(), 5s, log.options(300ms, connector.key));
  if (conn) {
    o.connector = net::handshake(*conn, make_hello(wire::Role::render_client), connector, 5s);
    o.connection = std::make_unique<net::Connection>(std::move(*conn));
    if (o.connector) o.connection->close("done");
  }
  server.join();
  return o;
}

net::PeerExpectation with_key(const net::ClusterKey* key) {
  net::PeerExpectation e;
  e.key = key;
  return e;
}

}  // namespace

TEST_F(Handshake, TheSameKeyOnBothSidesIsAccepted) {
  const net::ClusterKey a = key_of('k'), b = key_of('k');
  Outcomes o = handshake_both(*listener, with_key(&a), with_key(&b), log);
  ASSERT_TRUE(o.acceptor) << o.acceptor.error();
  ASSERT_TRUE(o.connector) << o.connector.error();
  EXPECT_EQ(o.connector->role, wire::Role::switch_node);
  EXPECT_EQ(o.connector->auth, wire::Auth::cluster_key);
  EXPECT_EQ(o.acceptor->auth, wire::Auth::cluster_key);
  EXPECT_NE(o.acceptor->nonce, wire::Nonce{});
  // Each side sent one hello and one proof.
  EXPECT_EQ(o.connection->stats().sent.messages_of(wire::Type::proof), 1u);
  EXPECT_EQ(o.connection->stats().received.messages_of(wire::Type::proof), 1u);
  EXPECT_TRUE(log.snapshot().empty());
}

// (A wrong key, or a key on one side only, fails in TLS before the hellos: net_tls_test.)
TEST_F(Handshake, AKeyForTheHandshakeOnlyOrTheConnectionOnlyFailsAtOnce) {
  const net::ClusterKey key = key_of('k');
  for (bool tls : {false, true}) {
    // The handshake has the key (expect.key) but the connection was made without (or the reverse).
    auto conn = net::Connection::connect("127.0.0.1", listener->port(), 5s, log.options(300ms, tls ? &key : nullptr));
    ASSERT_TRUE(conn) << conn.error();
    auto r = net::handshake(*conn, make_hello(wire::Role::render_client), with_key(tls ? nullptr : &key), 5s);
    ASSERT_FALSE(r);
    EXPECT_TRUE(contains(r.error(), tls ? "a TLS connection but no cluster key for the handshake"
                                        : "a cluster key for the handshake but a connection without TLS"))
        << r.error();
    EXPECT_EQ(conn->stats().sent.messages_of(wire::Type::hello), 0u) << "nothing sent";
  }
}

// A connector that plays the handshake by hand with the right key, sends its proof through
// `tweak`, and reports what the acceptor answered.
struct ManualConnector {
  net::Listener& listener;
  LogCapture& log;
  wire::Nonce nonce;
  wire::Hello acceptor_hello;

  Result<wire::Hello> run(const net::ClusterKey& node_key, const net::ClusterKey& my_key,
                          const std::function<wire::Proof(const wire::Proof& fresh)>& tweak,
                          std::vector<wire::Type>* answered) {
    Result<wire::Hello> acceptor = Error{"not run"};
    std::thread server([&] {
      auto conn = listener.accept(5s, log.options(300ms, &node_key));
      if (!conn) return;
      acceptor = net::handshake(*conn, make_hello(wire::Role::switch_node), with_key(&node_key), 5s);
    });
    // TLS with the node's key (the link is a given here); the proof made with my_key.
    auto conn = net::Connection::connect("127.0.0.1", listener.port(), 5s, log.options(300ms, &node_key));
    if (conn) {
      wire::Hello mine = make_hello(wire::Role::render_client);
      mine.auth = wire::Auth::cluster_key;
      mine.nonce = nonce;
      conn->send(mine);
      net::Received r = conn->receive(5s);
      if (auto* h = std::get_if<wire::Hello>(&r.message)) {
        acceptor_hello = *h;
        conn->send(tweak(my_key.prove(wire::ProofDirection::connector, mine, *h)));
        for (net::Received m = conn->receive(5s); m.ok(); m = conn->receive(5s))
          answered->push_back(wire::type_of(m.message));
      }
    }
    server.join();
    return acceptor;
  }
};

TEST_F(Handshake, InsideTlsAProofWithAnotherKeyIsRefusedAndTheAcceptorProvesNothing) {
  const net::ClusterKey key = key_of('k'), wrong = key_of('w');
  ManualConnector c{*listener, log, net::random_nonce(), {}};
  std::vector<wire::Type> answered;
  auto r = c.run(key, wrong, [](const wire::Proof& p) { return p; }, &answered);
  ASSERT_FALSE(r);
  EXPECT_TRUE(contains(r.error(), "cluster key mismatch: the proof of render_client 0 (\"test\") does not verify"))
      << r.error();
  EXPECT_TRUE(answered.empty());  // no proof of the acceptor's in return
}

TEST_F(Handshake, AReplayedProofIsRefused) {
  const net::ClusterKey key = key_of('k');
  ManualConnector c{*listener, log, net::random_nonce(), {}};
  std::vector<wire::Type> answered;
  wire::Proof recorded;
  // A genuine exchange, recorded by an eavesdropper...
  ASSERT_TRUE(c.run(key, key, [&](const wire::Proof& p) { return recorded = p; }, &answered));
  ASSERT_EQ(answered, std::vector<wire::Type>{wire::Type::proof});
  const wire::Nonce first_challenge = c.acceptor_hello.nonce;
  // ... replayed on a new connection with the same hello: the acceptor's challenge is new.
  answered.clear();
  auto replay = c.run(key, key, [&](const wire::Proof&) { return recorded; }, &answered);
  EXPECT_NE(c.acceptor_hello.nonce, first_challenge);
  ASSERT_FALSE(replay);
  EXPECT_TRUE(contains(replay.error(), "cluster key mismatch")) << replay.error();
  EXPECT_TRUE(answered.empty());  // no proof of the acceptor's in return
}

TEST_F(Handshake, ATamperedProofIsRefused) {
  const net::ClusterKey key = key_of('k');
  for (size_t byte : {0u, 17u, 31u}) {
    ManualConnector c{*listener, log, net::random_nonce(), {}};
    std::vector<wire::Type> answered;
    auto r = c.run(key, key, [&](wire::Proof p) { p.mac[byte] ^= 0x01; return p; }, &answered);
    ASSERT_FALSE(r) << "byte " << byte;
    EXPECT_TRUE(contains(r.error(), "cluster key mismatch")) << r.error();
    EXPECT_TRUE(answered.empty());
  }
}

TEST_F(Handshake, ARefusalTakesThePlaceOfTheAcceptorsLastMessage) {
  const net::ClusterKey key = key_of('k');
  for (const net::ClusterKey* k : {static_cast<const net::ClusterKey*>(nullptr), &key}) {
    net::PeerExpectation acceptor = with_key(k);
    std::string asked_about;
    acceptor.refuse = [&](const wire::Hello& h) {
      asked_about = std::string(wire::role_name(h.role));
      return std::optional<std::string>("busy: node 0 is serving another render client");
    };
    Outcomes o = handshake_both(*listener, acceptor, with_key(k), log);
    ASSERT_FALSE(o.acceptor);
    ASSERT_FALSE(o.connector) << "the connector's handshake must fail, not succeed and then read a bye";
    EXPECT_EQ(asked_about, "render_client");
    EXPECT_TRUE(contains(o.connector.error(), "peer said bye: busy: node 0 is serving another render client"))
        << o.connector.error();
    EXPECT_EQ(o.connector.error_kind(), ErrorKind::busy) << "a kind to act on, not the text";
    EXPECT_EQ(o.acceptor.error_kind(), ErrorKind::other);
    EXPECT_EQ(o.connection->stats().received.messages_of(wire::Type::hello), k ? 1u : 0u);
    EXPECT_EQ(o.connection->stats().received.messages_of(wire::Type::proof), 0u);
  }
}
