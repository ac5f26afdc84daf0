// TCP transport for the wire protocol (Boost.Asio inside, not in this header).
//
// Connection: one framed TCP stream, usable from plain threads. With a cluster key
// (ConnectionOptions::key) the stream is TLS 1.3 with a pre-shared key derived from it
// (protocol/net/tls.hpp, docs/security.md): the io thread runs the TLS handshake first, and every
// message after it is encrypted and authenticated. A failed TLS handshake, or a record altered
// on the way, ends the connection as an error like any other (one line naming the peer). A private io thread reads whole
// frames (header first, validated before the payload buffer is sized) into an inbox and drains
// a write queue; TCP_NODELAY is on. Several owner threads may send(); one thread receives.
// Nothing blocks without a bound: send() waits at most send_timeout for queue space, receive()
// at most its timeout, close() at most close_linger.
//
// How a connection ends (receive() reports it after the messages that arrived before it):
//   closed  the peer sent Bye, or we called close(): both sides say why in the Bye.
//   error   bad input (decode error, disconnect mid-message, EOF without Bye), an I/O error,
//           a peer that stops reading, or close_with_error(). Exactly one line is logged
//           ("occ_net: peer 127.0.0.1:40312: <reason>"), stats().errors counts it, and if the
//           socket still works the peer gets Bye(reason) before the close.
#pragma once
#include <array>
#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>

#include "protocol/result.hpp"
#include "protocol/wire.hpp"

namespace occ::net {

using Millis = std::chrono::milliseconds;

struct TrafficStats {
  uint64_t bytes = 0;  // header + payload
  uint64_t messages = 0;
  std::array<uint64_t, wire::kTypeCount> bytes_by_type{};     // index: wire::type_index()
  std::array<uint64_t, wire::kTypeCount> messages_by_type{};
  uint64_t bytes_of(wire::Type t) const { return bytes_by_type[wire::type_index(t)]; }
  uint64_t messages_of(wire::Type t) const { return messages_by_type[wire::type_index(t)]; }
};

struct ConnectionStats {
  TrafficStats sent;      // counted when send() queues the message (Bye included)
  TrafficStats received;  // counted when a message is decoded
  uint64_t errors = 0;    // 0 or 1: the error that ended the connection
  // Bytes through the socket (TCP payload), counted as the socket takes or gives them: the
  // messages plus, with TLS, its handshake and each record's header and tag.
  uint64_t socket_bytes_sent = 0;
  uint64_t socket_bytes_received = 0;
};

class ClusterKey;  // protocol/net/auth.hpp

struct ConnectionOptions {
  size_t max_send_queue_bytes = 8u << 20;     // send() waits while this much is queued ...
  Millis send_timeout{10000};                 // ... this long at most, then the connection fails
  size_t max_receive_queue_bytes = 16u << 20; // reading pauses while this much awaits receive()
  Millis close_linger{1000};                  // time for queued data and the Bye to drain
  // Receives the one log line of a failed connection (called with an internal lock held: must
  // not call back into the Connection). Default: the line goes to stderr.
  std::function<void(const std::string& line)> log;
  // The cluster key: TLS 1.3 with a PSK derived from it (both sides need the same key); nullptr:
  // plain TCP. Read by connect()/accept() only (it need not outlive them). handshake() wants the
  // same key in PeerExpectation::key.
  const ClusterKey* key = nullptr;
};

// Default options with the cluster key `key` (nullptr: none), for a cluster's connections.
inline ConnectionOptions keyed_options(const ClusterKey* key) {
  ConnectionOptions o;
  o.key = key;
  return o;
}

struct Received {
  enum class Status { message, timeout, closed, error };
  Status status = Status::timeout;
  wire::Message message;  // valid when status == message
  // Bytes of this message on the wire (header + payload; TLS's records add theirs, counted in
  // ConnectionStats::socket_bytes_received), so a reader can attribute traffic to what it
  // belongs to: stats().received counts when the io thread decodes, which may be ahead.
  size_t wire_bytes = 0;
  std::string reason;     // closed / error: why, without the peer address (see peer())
  bool busy = false;      // closed: by the peer's Bye refusing us as busy (wire.hpp kByeBusy)
  bool ok() const { return status == Status::message; }
};

class Connection {
 public:
  // Connects to host:port, retrying every 50 ms while nobody listens there yet (peers start in
  // any order), for at most retry_timeout.
  static Result<Connection> connect(const std::string& host, uint16_t port, Millis retry_timeout,
                                    ConnectionOptions options = {});

  Connection(Connection&&) noexcept;
  Connection& operator=(Connection&&) noexcept;
  ~Connection();  // close("connection closed")

  // Thread-safe. Validates (wire::invalid_reason), encodes and queues the message; waits while
  // the send queue is full. nullopt once queued, else why not: invalid message, connection ended,
  // or the queue stayed full for send_timeout (the peer is not reading: the connection fails).
  std::optional<std::string> send(const wire::Message& message);

  // One receiving thread. Waits up to `timeout` for the next message, then reports the end of
  // the connection (forever) once the messages received before it are consumed.
  Received receive(Millis timeout);

  // Thread-safe, idempotent: sends Bye(reason), lets queued data drain, closes; returns when the
  // socket is closed (at most close_linger). Messages already received stay readable.
  void close(const std::string& reason);
  // Ends the connection because the peer misbehaved (e.g. a wrong hello): logs one line, counts
  // the error, sends Bye(reason), closes. Turns a closed connection into an error; no-op on one
  // that already failed. Does not wait.
  void close_with_error(const std::string& reason);

  bool is_open() const;
  // Made by Listener::accept (the acceptor of the handshake) rather than connect().
  bool accepted() const;
  // Runs TLS (made with ConnectionOptions::key).
  bool encrypted() const;
  ConnectionStats stats() const;
  const std::string& peer() const;  // "127.0.0.1:40312"

 private:
  struct Impl;
  explicit Connection(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
  friend class Listener;
};

// What a handshake accepts besides our own scene fingerprint and build parameters.
struct PeerExpectation {
  std::optional<wire::Role> role;     // nullopt: any role
  std::optional<uint8_t> node_id;     // nullopt: any node id
  bool same_viewport = true;          // the peer's viewport must equal ours
  // The cluster key (docs/security.md): both sides prove it, or neither has one. nullptr: none.
  // The connection must have been made with the same key (ConnectionOptions::key: TLS), or none.
  const ClusterKey* key = nullptr;
  // The acceptor only: asked once the connector's hello (and key) passed; a reason refuses it
  // (the connector gets Bye(reason) instead of our last handshake message), e.g. "busy: ...".
  std::function<std::optional<std::string>(const wire::Hello& peer)> refuse{};
};

// Both sides call this first (the message order is in wire.hpp, "Handshake"): exchanges Hellos
// (the one that connected sends first), waits up to `timeout` in all and checks the peer's
// (magic and version in the decoder; scene fingerprint, arity, leaf_items, cluster_triangles,
// config_hash equal to ours; then `expect`), then, with expect.key, the HMAC challenge-response
// (inside TLS: a second proof of the key, bound to both hellos). A connection that is not TLS
// while expect.key is set (or the reverse) fails at once: the caller forgot ConnectionOptions::key.
// `mine`'s auth and nonce are set here (a fresh nonce per call). On failure the connection is
// ended with close_with_error, so the peer gets a Bye saying why, and the error names the peer
// and both values: "peer 127.0.0.1:5555: scene fingerprint mismatch: ours 0x..., peer has 0x...".
// Its kind: busy when the acceptor refused us with a kByeBusy reason (expect.refuse), else other.
Result<wire::Hello> handshake(Connection& conn, const wire::Hello& mine,
                              const PeerExpectation& expect, Millis timeout);

struct Peer {
  Connection connection;
  wire::Hello hello;
};

// Use one Listener from one thread at a time.
class Listener {
 public:
  // Binds address:port and listens; port 0 lets the OS pick a free port (see port()). Loopback
  // only unless another address is asked for.
  static Result<Listener> open(uint16_t port, const std::string& address = "127.0.0.1");

  Listener(Listener&&) noexcept;
  Listener& operator=(Listener&&) noexcept;
  ~Listener();

  uint16_t port() const;
  const std::string& address() const;

  // Waits up to `timeout` for one incoming connection (no handshake); ErrorKind::timeout when none came.
  Result<Connection> accept(Millis timeout, ConnectionOptions options = {});

  // Accepts until a peer passes handshake(mine, expect) or overall_timeout passes. Strangers
  // (garbage, no hello within hello_timeout, a wrong hello) are logged by their connection,
  // counted in rejected(), closed, and the wait goes on. ErrorKind::timeout when no peer passed
  // within overall_timeout ("no valid peer on ..."); other when accepting failed.
  Result<Peer> accept_peer(const wire::Hello& mine, const PeerExpectation& expect,
                           Millis overall_timeout, Millis hello_timeout = Millis(2000),
                           ConnectionOptions options = {});
  uint64_t rejected() const;

 private:
  struct Impl;
  explicit Listener(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

// --port 0 / --port-file F support: writes "<port>\n" atomically (temp file, then rename), so a
// reader never sees a partial file. nullopt on success, else the reason.
std::optional<std::string> write_port_file(const std::string& path, uint16_t port);
// Waits up to `timeout` (polling every 10 ms) for a port file to appear and reads it.
Result<uint16_t> read_port_file(const std::string& path, Millis timeout);

}  // namespace occ::net
