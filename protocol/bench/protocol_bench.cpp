// protocol_bench: throughput of NodeDiff streams over loopback, as the HC node would send them
// (chunks of b ids, then EndOfFrame), received, rebuilt and verified as OR/RVG would. Prints
// messages/s, ids/s and MB/s, and the paper's per-frame byte formula (3.5) next to ours.
// Usage: protocol_bench [--seconds S]
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <iomanip>
#include <iostream>
#include <stdexcept>
#include <thread>

#include "common/cli.hpp"
#include "protocol/net/transport.hpp"
#include "protocol/visible_set.hpp"

using namespace occ;
using Clock = std::chrono::steady_clock;

namespace {

constexpr uint32_t kIdLimit = 100000;
constexpr uint32_t kVisible = 20000;  // |V_f|

wire::Hello hello(wire::Role role) {
  wire::Hello h;
  h.role = role;
  h.scene_fingerprint = 0xbe7c4;
  h.name = "protocol_bench";
  return h;
}

struct RunResult {
  double seconds = 0;
  uint64_t frames = 0, messages = 0, ids = 0, bytes = 0;
};

uint64_t stream_bytes(const net::ConnectionStats& s) {
  return s.sent.bytes_of(wire::Type::node_diff) + s.sent.bytes_of(wire::Type::end_of_frame);
}
uint64_t stream_messages(const net::ConnectionStats& s) {
  return s.sent.messages_of(wire::Type::node_diff) + s.sent.messages_of(wire::Type::end_of_frame);
}

// Sends frame `frame`: the diff from cur to next in chunks of b, then EndOfFrame.
std::optional<std::string> send_frame(net::Connection& conn, uint32_t frame, uint32_t b,
                                      const VisibleSet& cur, const VisibleSet& next) {
  const SetDiff d = diff_sets(cur, next);
  for (auto& chunk : wire::chunk_node_diff(frame, d.added, d.removed, b))
    if (auto e = conn.send(chunk)) return e;
  return conn.send(make_end_of_frame(frame, d, next));
}

// Frame 0 sends the initial V (a window of kVisible ids); then, for about `seconds`, each frame
// slides the window by changes/2 ids (changes/2 added, changes/2 removed). The clock stops when
// the receiver has rebuilt and verified every frame.
RunResult run(uint32_t b, uint32_t changes, double seconds) {
  auto listener = net::Listener::open(0);
  if (!listener) throw std::runtime_error(listener.error());
  std::string receiver_error;
  std::thread receiver([&] {
    auto peer = listener->accept_peer(hello(wire::Role::render_client), {}, net::Millis(5000));
    if (!peer) return void(receiver_error = peer.error());
    VisibleSet v(kIdLimit);
    DiffReceiver rx;
    for (;;) {
      net::Received r = peer->connection.receive(net::Millis(5000));
      if (r.status == net::Received::Status::closed) return;
      if (!r.ok()) return void(receiver_error = r.reason);
      std::optional<std::string> e;
      if (auto* d = std::get_if<wire::NodeDiff>(&r.message)) e = rx.on_diff(v, *d);
      if (auto* eof = std::get_if<wire::EndOfFrame>(&r.message)) e = rx.on_end_of_frame(v, *eof);
      if (e) return void(receiver_error = *e);
    }
  });

  RunResult result;
  std::optional<std::string> error;
  Clock::time_point t0;
  uint64_t bytes0 = 0, messages0 = 0;
  if (auto conn = net::Connection::connect("127.0.0.1", listener->port(), net::Millis(5000));
      !conn) {
    error = conn.error();
  } else if (auto h = net::handshake(*conn, hello(wire::Role::switch_node), {}, net::Millis(5000));
             !h) {
    error = h.error();
  } else {
    // cur = V_{f-1}, next = V_f: both get the same edits, one frame apart (no set copies).
    VisibleSet cur(kIdLimit), next(kIdLimit);
    for (uint32_t id = 0; id < kVisible; ++id) next.insert(id);
    error = send_frame(*conn, 0, b, cur, next);
    for (uint32_t id = 0; id < kVisible; ++id) cur.insert(id);
    const auto slide = [&](VisibleSet& v, uint32_t start) {
      for (uint32_t i = 0; i < changes / 2; ++i) {
        v.erase((start + i) % kIdLimit);
        v.insert((start + kVisible + i) % kIdLimit);
      }
    };
    bytes0 = stream_bytes(conn->stats());
    messages0 = stream_messages(conn->stats());
    t0 = Clock::now();
    uint32_t window_start = 0;
    for (uint32_t frame = 1;
         !error && std::chrono::duration<double>(Clock::now() - t0).count() < seconds; ++frame) {
      slide(next, window_start);
      error = send_frame(*conn, frame, b, cur, next);
      slide(cur, window_start);
      window_start = (window_start + changes / 2) % kIdLimit;
      result.frames += 1;
      result.ids += changes;
    }
    result.bytes = stream_bytes(conn->stats()) - bytes0;
    result.messages = stream_messages(conn->stats()) - messages0;
    conn->close("benchmark done");
  }
  receiver.join();
  result.seconds = std::chrono::duration<double>(Clock::now() - t0).count();
  if (error) throw std::runtime_error("sender: " + *error + "; receiver: " + receiver_error);
  if (!receiver_error.empty()) throw std::runtime_error("receiver: " + receiver_error);
  return result;
}

}  // namespace

int main(int argc, char** argv) {
  double seconds = 2.0;
  Cli cli("protocol_bench", "[--seconds S]",
          "Throughput of NodeDiff streams over 127.0.0.1 as the HC node sends them (chunks of b ids, then\n"
          "EndOfFrame), rebuilt and verified by the receiver; prints messages/s, ids/s and MB/s for b = 100\n"
          "and 1000, and the paper's bytes-per-frame formula next to this encoding. Asserts nothing.");
  cli.option("seconds", &seconds, 0.01, 60, "seconds per run");
  bool go = true;
  const int code = run_main([&] {
    go = cli.parse(argc, argv);
    return 0;
  });
  if (code != 0 || !go) return code;
  std::cout << std::fixed << std::setprecision(1);
  std::cout << "NodeDiff streams over 127.0.0.1 (|V| = " << kVisible << ", ids rebuilt and "
            << "verified by the receiver, " << seconds << " s per run)\n";
  std::cout << "   b  ids/frame   frames/s     msgs/s        ids/s      MB/s\n";
  try {
    for (auto [b, changes] : {std::pair{100u, 2000u}, std::pair{1000u, 2000u}}) {
      const RunResult r = run(b, changes, seconds);
      std::cout << std::setw(4) << b << std::setw(11) << changes << std::setprecision(0)
                << std::setw(11) << r.frames / r.seconds << std::setw(11) << r.messages / r.seconds
                << std::setw(13) << r.ids / r.seconds << std::setprecision(1) << std::setw(10)
                << r.bytes / r.seconds / 1e6 << "\n";
    }
  } catch (const std::exception& e) {
    std::cerr << "error: " << e.what() << "\n";
    return 1;
  }

  // Paper 3.5: per-frame bytes 8n + nh/b + 3(72 + h), h = 50 (TCP/IP/Ethernet headers), b = 100.
  // Ours, one frame: diff chunks + EndOfFrame to OR and to RVG, and four cameras (the render
  // client's to both nodes, the HC node's to the render client and to the other node). The n ids
  // are taken as one list (added and removed chunks are split separately: a few more headers).
  const double h = 50, b = 100;
  const auto frame_bytes = [&](double n) {
    const double chunks = std::ceil(n / b);
    const double diff = chunks * (wire::kHeaderBytes + 12) + 4 * n;
    const double eof = static_cast<double>(wire::encode(wire::EndOfFrame{}).size());
    const double camera = static_cast<double>(wire::encode(wire::Camera{}).size());
    return std::pair{2 * (diff + eof) + 4 * camera, 2 * (chunks + 1) * h + 4 * h};
  };
  std::cout << "\nbytes per frame (b = 100, h = 50): paper 8n + nh/b + 3(72 + h) vs this encoding\n"
            << "      n      paper       ours  ours + h per message\n";
  for (double n : {0.0, 100.0, 1000.0, 4000.0}) {
    const double paper = 8 * n + n * h / b + 3 * (72 + h);
    const auto [ours, headers] = frame_bytes(n);
    std::cout << std::setprecision(0) << std::setw(7) << n << std::setw(11) << paper
              << std::setw(11) << ours << std::setw(11) << ours + headers << "\n";
  }
  return 0;
}
