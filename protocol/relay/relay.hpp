// Link emulator: a TCP relay between two processes that adds one-way delay, jitter and a
// bandwidth cap, per direction, and can stall, cut or alter the link on command. Protocol-agnostic: it
// forwards raw bytes and parses nothing. The kernel here has no netem; this is its user-space
// stand-in for tests and benchmarks of the cluster (see link_relay --help).
//
// Each accepted connection is forwarded to the target (connect retried every 50 ms, for at most
// connect_timeout, since the target may start later) and gets two independent pipes:
// up (client -> target) and down (target -> client). Per pipe, a chunk of n bytes read at t:
//   - occupies the link for n*8/rate s, from max(t, end of the previous chunk's transmission)
//     (serialisation model; rate 0 = unlimited). Chunks are at most ~2 ms of transmission time
//     (>= 1500 B, <= 64 KiB), so a capped stream flows smoothly;
//   - is written to the other side at
//       max(previous chunk's release, transmission end + max(0, delay + U(-jitter, +jitter)))
//     so jitter never reorders bytes;
//   - counts as queued from read to written. While queued > max_queued_bytes the pipe stops
//     reading: the sender sees ordinary TCP backpressure. Memory per pipe <= that + one chunk.
// Nothing is lost, duplicated or reordered. EOF is forwarded (shutdown of the send side) after
// the queued bytes; when both pipes have forwarded EOF the connection closes. An error on
// either socket (reset, write to a closed peer) closes both sockets abruptly (RST), dropping
// what was queued. TCP_NODELAY is set on every socket.
//
// Control (stall / resume / cut / stats) is relay-wide, applying to all connections:
//   stall   stop writing; reading goes on until the queue limit (then backpressure).
//   resume  write again: chunks whose release time passed during the stall go out at once.
//   cut     close every open connection abruptly on both sides (RST, queued bytes dropped).
//           The relay keeps accepting new connections.
// The same commands come as text lines on an optional control port (127.0.0.1 only, one line
// in, one line out, several commands per control connection):
//   "stall" -> "ok stalled"      "resume" -> "ok resumed"      "cut" -> "ok cut <n connections>"
//   "flip"  -> "ok flip armed": one byte of the next chunk read from the target (on any connection)
//              is inverted on its way to the client: tampering, for tests of the links' integrity
//   "stats" -> "up=<bytes> down=<bytes> queued_up=<bytes> queued_down=<bytes> open=<n>
//               accepted=<n> stalled=<0|1>"     (bytes forwarded per direction since start)
//   other   -> "error: unknown command '<line>' (stall|resume|cut|flip|stats)"
#pragma once
#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>

#include "protocol/result.hpp"

namespace occ::relay {

using Millis = std::chrono::milliseconds;

struct LinkParams {
  double delay_ms = 0;   // one-way delay
  double jitter_ms = 0;  // uniform in [-jitter, +jitter] added to the delay (never reorders)
  double rate_mbit = 0;  // bandwidth cap in Mbit/s (10^6 bit/s); 0 = unlimited
};

struct RelayOptions {
  std::string listen_address = "127.0.0.1";
  uint16_t listen_port = 0;  // 0: the OS picks a free port (see Relay::port())
  std::string target_host = "127.0.0.1";
  uint16_t target_port = 0;
  LinkParams up;    // client -> target
  LinkParams down;  // target -> client
  uint64_t seed = 1;                   // jitter RNG: pipe k of connection c uses seed, c, k
  Millis connect_timeout{10000};       // per accepted connection, for reaching the target
  size_t max_queued_bytes = 8u << 20;  // per pipe; reading pauses above it
  bool control = false;                // open the control port (127.0.0.1, free port)
  // Receives one line per connection opened / closed (with bytes per direction), e.g.
  //   "conn 2 open 127.0.0.1:40312 -> 127.0.0.1:5555"
  //   "conn 2 closed (eof) up 1200 B down 53000 B"
  // Called on the relay's thread; must not call back into the Relay. Default: stderr.
  std::function<void(const std::string& line)> log;
};

struct RelayStats {
  uint64_t up_bytes = 0, down_bytes = 0;      // forwarded (written), all connections so far
  uint64_t queued_up = 0, queued_down = 0;    // read but not yet written, open connections
  uint64_t open = 0, accepted = 0;            // connections
  bool stalled = false;
  std::string line() const;  // the control channel's "stats" answer, without the newline
};

// A running relay: one io thread does all socket work. Public methods are thread-safe and must
// not be called from the log callback.
class Relay {
 public:
  // Resolves the target, binds and listens (and the control port if asked), starts the thread.
  static Result<Relay> start(RelayOptions options);

  Relay(Relay&&) noexcept;
  Relay& operator=(Relay&&) noexcept;
  ~Relay();  // closes every connection ("relay stopped") and joins the thread

  uint16_t port() const;
  uint16_t control_port() const;  // 0 without options.control

  void stall();
  void resume();
  size_t cut();  // returns the number of connections cut
  RelayStats stats() const;

 private:
  struct Impl;
  explicit Relay(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace occ::relay
