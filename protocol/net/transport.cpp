#include "protocol/net/transport.hpp"

#include "protocol/net/deadline.hpp"
#include "protocol/net/tls.hpp"

#include <algorithm>
#include <condition_variable>
#include <cstdio>
#include <deque>
#include <iostream>
#include <mutex>
#include <thread>

#include "protocol/net/asio_names.hpp"

namespace occ::net {
using namespace asio_names;

namespace {

std::string endpoint_string(const tcp::endpoint& ep) {
  return ep.address().to_string() + ":" + std::to_string(ep.port());
}

// Bye text from any reason: printable ASCII only, at most kMaxReasonBytes (always valid).
std::string bye_text(const std::string& reason) {
  std::string s = reason.substr(0, wire::kMaxReasonBytes);
  for (char& c : s)
    if (c < 0x20 || c > 0x7e) c = '?';
  return s;
}

// A keyless connection's reason when the peer's first bytes are a TLS record.
const std::string kPeerSpeaksTls =
    "the peer speaks TLS: it has a cluster key (--cluster-key-file), this process has none";

void count(TrafficStats& s, wire::Type t, size_t bytes) {
  s.bytes += bytes;
  s.messages += 1;
  s.bytes_by_type[wire::type_index(t)] += bytes;
  s.messages_by_type[wire::type_index(t)] += 1;
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// Connection
//
// Threads: the owner's threads call send/receive/close; the io thread runs every socket
// operation and handler. Shared state is guarded by `m`; the socket and the fields marked
// "io thread" are touched only by the io thread once start() has run.
// Lifecycle: open -> ended (end != none: no more sends, a Bye may be queued) -> wind_down():
// drain the write queue, shutdown(send), discard input until the peer's EOF or close_linger
// -> force_close(): socket closed, `finished`.

struct Connection::Impl {
  enum class End { none, closed, error };

  explicit Impl(ConnectionOptions o) : opts(std::move(o)), sock(io), linger_timer(io) {}

  ConnectionOptions opts;
  asio::io_context io;
  tcp::socket sock;
  asio::steady_timer linger_timer;
  std::atomic<uint64_t> wire_in{0}, wire_out{0};  // bytes through the socket
  CountedSocket wire{sock, wire_in, wire_out};
  std::unique_ptr<tls::Context> tls_context;  // with a key (set in start())
  std::optional<tls::Stream> tls;             // over `wire`; the messages go through it
  std::optional<asio::executor_work_guard<asio::io_context::executor_type>> work;
  std::thread thread;
  std::string peer = "unknown";
  bool accepted = false;  // made by Listener::accept (the acceptor in the handshake)

  mutable std::mutex m;
  std::condition_variable cv_in;   // inbox or end changed
  std::condition_variable cv_out;  // send queue space, end or finished changed
  struct Inbound {
    wire::Message message;
    size_t wire_bytes;  // header + payload as received
    size_t cost;        // memory estimate (bytes)
  };
  std::deque<Inbound> inbox;
  size_t inbox_bytes = 0;  // sum of the estimates
  std::deque<std::vector<uint8_t>> outbox;  // queued, not yet handed to the socket
  size_t outbox_bytes = 0;                  // queued + in flight
  bool writing = false;                     // a start_write is posted or a write is in flight
  bool read_paused = false;                 // inbox full: no read outstanding
  End end = End::none;
  std::string end_reason;
  bool busy_bye = false;  // ended by the peer's Bye refusing us as busy (wire::kByeBusy)
  bool finished = false;  // socket closed
  ConnectionStats stats;

  // io thread
  std::array<uint8_t, wire::kHeaderBytes> header{};
  wire::Type payload_type = wire::Type::hello;
  std::vector<uint8_t> payload;
  std::vector<std::vector<uint8_t>> inflight;
  size_t inflight_bytes = 0;
  std::array<uint8_t, 4096> discard_buf{};
  bool read_pending = false;
  bool peer_eof = false;
  bool shutdown_sent = false;
  bool linger_started = false;
  bool tls_ready = false;  // the TLS handshake is done: messages may flow

  void start() {
    error_code ec;
    sock.set_option(tcp::no_delay(true), ec);
    auto ep = sock.remote_endpoint(ec);
    if (!ec) peer = endpoint_string(ep);
    if (opts.key) {
      tls_context = std::make_unique<tls::Context>(*opts.key, accepted);
      tls.emplace(wire, tls_context->native());
      opts.key = nullptr;  // the context holds the PSK: the key need not outlive connect()/accept()
    }
    io.restart();
    work.emplace(io.get_executor());
    asio::post(io, [this] { tls ? start_tls() : read_header(); });
    thread = std::thread([this] { io.run(); });
  }

  // Every read and write of messages: through TLS with a key, else straight through the socket.
  template <class Buffers, class Handler>
  void read_exactly(const Buffers& b, Handler&& h) {
    if (tls) asio::async_read(*tls, b, std::forward<Handler>(h));
    else asio::async_read(wire, b, std::forward<Handler>(h));
  }
  template <class Buffers, class Handler>
  void write_all(const Buffers& b, Handler&& h) {
    if (tls) asio::async_write(*tls, b, std::forward<Handler>(h));
    else asio::async_write(wire, b, std::forward<Handler>(h));
  }

  void stop() {  // owner thread, once, from ~Connection
    if (!thread.joinable()) return;
    close("connection closed");
    asio::post(io, [this] { force_close(); });
    work.reset();
    thread.join();
  }

  // ---- owner side ----

  std::optional<std::string> send(const wire::Message& msg) {
    if (auto e = wire::invalid_reason(msg)) return "cannot send invalid message: " + *e;
    std::vector<uint8_t> bytes = wire::encode(msg);
    std::unique_lock lk(m);
    const bool space = cv_out.wait_for(lk, std::clamp(opts.send_timeout, Millis(0), kMaxWait), [&] {
      return end != End::none || outbox_bytes < opts.max_send_queue_bytes;
    });
    if (end != End::none) return "connection ended: " + end_reason;
    if (!space) {
      const std::string reason =
          "send queue full for " + std::to_string(opts.send_timeout.count()) + " ms (" +
          std::to_string(outbox_bytes) + " bytes queued): peer is not reading";
      end_locked(End::error, reason, Ending::abort);
      return reason;
    }
    queue_locked(std::move(bytes), wire::type_of(msg));
    return std::nullopt;
  }

  Received receive(Millis timeout) {
    timeout = std::clamp(timeout, Millis(0), kMaxWait);
    std::unique_lock lk(m);
    cv_in.wait_for(lk, timeout, [&] { return !inbox.empty() || end != End::none; });
    Received r;
    if (!inbox.empty()) {
      r.status = Received::Status::message;
      r.message = std::move(inbox.front().message);
      r.wire_bytes = inbox.front().wire_bytes;
      inbox_bytes -= inbox.front().cost;
      inbox.pop_front();
      if (read_paused && inbox_bytes <= opts.max_receive_queue_bytes / 2) {
        read_paused = false;
        asio::post(io, [this] { read_header(); });
      }
    } else if (end != End::none) {
      r.status = end == End::closed ? Received::Status::closed : Received::Status::error;
      r.reason = end_reason;
      r.busy = busy_bye;
    }
    return r;
  }

  void close(const std::string& reason) {
    std::unique_lock lk(m);
    end_locked(End::closed, "closed locally: " + reason, Ending::bye, reason);
    cv_out.wait_for(lk, std::clamp(opts.close_linger, Millis(0), kMaxWait) + Millis(500),
                    [&] { return finished; });
  }

  void close_with_error(const std::string& reason) {
    std::lock_guard lk(m);
    if (end == End::closed) {  // already winding down: only the verdict changes
      end_error_locked(reason);
      return;
    }
    end_locked(End::error, reason, Ending::bye);
  }

  // ---- shared helpers (m held) ----

  enum class Ending { bye, quiet, abort };

  // Ends the connection once: records the verdict, logs an error, and starts the close.
  void end_locked(End kind, const std::string& reason, Ending how,
                  const std::string& bye_reason = {}) {
    if (end != End::none) return;
    if (kind == End::error) {
      end_error_locked(reason);
    } else {
      end = kind;
      end_reason = reason;
    }
    cv_in.notify_all();
    cv_out.notify_all();
    if (how == Ending::abort) return asio::post(io, [this] { force_close(); });
    if (how == Ending::bye)
      queue_locked(wire::encode(wire::Bye{bye_text(bye_reason.empty() ? reason : bye_reason)}),
                   wire::Type::bye);
    asio::post(io, [this] { wind_down(); });
  }

  void end_error_locked(const std::string& reason) {
    end = End::error;
    end_reason = reason;
    ++stats.errors;
    const std::string line = "occ_net: peer " + peer + ": " + reason;
    if (opts.log) opts.log(line);
    else std::cerr << line << std::endl;
    cv_in.notify_all();
  }

  void queue_locked(std::vector<uint8_t> bytes, wire::Type type) {
    count(stats.sent, type, bytes.size());
    outbox_bytes += bytes.size();
    outbox.push_back(std::move(bytes));
    if (!writing) {
      writing = true;
      asio::post(io, [this] { start_write(); });
    }
  }

  // ---- io thread: TLS (with a key), before any message ----

  void start_tls() {
    read_pending = true;  // wind_down() waits for the handshake as for a read
    const auto side = accepted ? asio::ssl::stream_base::server : asio::ssl::stream_base::client;
    tls->async_handshake(side, [this](error_code ec) {
      read_pending = false;
      if (!sock.is_open()) return;
      if (ec) {
        peer_eof = true;
        if (auto refusal = tls::plaintext_refusal(ec); accepted && !refusal.empty()) {
          error_code ignored;  // a few bytes into an empty socket buffer: does not block
          wire_out += asio::write(sock, asio::buffer(refusal.data(), refusal.size()), ignored);
        }
        std::lock_guard lk(m);
        return end_locked(End::error, tls::handshake_failure(ec), Ending::abort);
      }
      tls_ready = true;
      bool queued = false;
      {
        std::lock_guard lk(m);
        queued = writing;
      }
      if (queued) start_write();
      read_header();
    });
  }

  // ---- io thread: reading ----

  bool ended() {
    std::lock_guard lk(m);
    return end != End::none;
  }

  void read_header() {
    if (!sock.is_open() || read_pending) return;
    if (ended()) return wind_down();  // wind_down owns reading now
    read_pending = true;
    read_exactly(asio::buffer(header), [this](error_code ec, size_t n) {
      if (after_read(ec)) return;
      if (ec) return read_failed(ec, n, "header", header.size());
      auto h = wire::decode_header(header);
      if (!h) return protocol_error(!tls && tls::looks_like_tls(header) ? kPeerSpeaksTls : h.error());
      payload_type = h->type;
      payload.resize(h->payload_bytes);  // <= kMaxPayloadBytes, checked by decode_header
      read_payload();
    });
  }

  void read_payload() {
    read_pending = true;
    read_exactly(asio::buffer(payload), [this](error_code ec, size_t n) {
      if (after_read(ec)) return;
      if (ec)
        return read_failed(ec, n, std::string(wire::type_name(payload_type)) + " payload",
                           payload.size());
      auto msg = wire::decode_payload(payload_type, payload);
      if (!msg) return protocol_error(msg.error());
      deliver(std::move(*msg), wire::kHeaderBytes + payload.size());
    });
  }

  // Common start of read handlers: true when the handler must not go on parsing.
  bool after_read(const error_code& ec) {
    read_pending = false;
    if (!sock.is_open()) return true;
    if (!ended()) return false;
    if (ec) peer_eof = true;
    wind_down();
    return true;
  }

  void deliver(wire::Message msg, size_t bytes) {
    std::unique_lock lk(m);
    count(stats.received, wire::type_of(msg), bytes);
    if (auto* bye = std::get_if<wire::Bye>(&msg)) {
      busy_bye = end == End::none && bye->reason.starts_with(wire::kByeBusy);  // the wire's refusal
      end_locked(End::closed, "peer said bye: " + bye->reason, Ending::quiet);
      return;
    }
    const size_t cost = bytes + sizeof(wire::Message);  // bounds memory for tiny messages too
    inbox.push_back({std::move(msg), bytes, cost});
    inbox_bytes += cost;
    cv_in.notify_one();
    if (inbox_bytes > opts.max_receive_queue_bytes) {
      read_paused = true;
      return;
    }
    lk.unlock();
    read_header();
  }

  void read_failed(const error_code& ec, size_t got, const std::string& what, size_t want) {
    peer_eof = true;
    const bool disconnected = ec == asio::error::eof || ec == asio::error::connection_reset ||
                              ec == asio::ssl::error::stream_truncated;
    std::string reason;
    if (!tls && what == "header" && tls::looks_like_tls(std::span(header).first(got)))
      reason = kPeerSpeaksTls;
    else if (ec == asio::error::eof && got == 0 && what == "header")
      reason = "peer closed the connection without bye";
    else if (disconnected && (got > 0 || what != "header"))
      reason = "peer disconnected mid-message (" + std::to_string(got) + " of " +
               std::to_string(want) + " " + what + " bytes)";
    else if (reason = tls::read_failure(ec); reason.empty())
      reason = "read error: " + ec.message();
    std::lock_guard lk(m);
    end_locked(End::error, reason, Ending::abort);
  }

  void protocol_error(const std::string& reason) {
    std::lock_guard lk(m);
    end_locked(End::error, reason, Ending::bye, "protocol error: " + reason);
  }

  // ---- io thread: writing and closing ----

  void start_write() {
    if (tls && !tls_ready) return;  // `writing` stays set: start_tls() calls back
    {
      std::lock_guard lk(m);
      // A write is in flight: its completion goes on with the outbox. (The TLS handshake's end
      // and a start_write the owner posted meanwhile both call this; the second wrote the first's
      // bytes again.)
      if (!inflight.empty()) return;
      inflight_bytes = 0;
      for (auto& b : outbox) {
        inflight_bytes += b.size();
        inflight.push_back(std::move(b));
      }
      outbox.clear();
    }
    if (!sock.is_open()) return;
    if (tls && inflight.size() > 1) {  // one TLS record (up to 16 KiB) for many small messages
      for (size_t i = 1; i < inflight.size(); ++i) inflight[0].insert(inflight[0].end(), inflight[i].begin(), inflight[i].end());
      inflight.resize(1);
    }
    std::vector<asio::const_buffer> buffers;
    buffers.reserve(inflight.size());
    for (const auto& b : inflight) buffers.push_back(asio::buffer(b));
    write_all(buffers, [this](error_code ec, size_t) {
      if (!sock.is_open()) return;
      std::unique_lock lk(m);
      if (ec) {
        end_locked(End::error, "write error: " + ec.message(), Ending::quiet);
        lk.unlock();
        return force_close();
      }
      inflight.clear();
      outbox_bytes -= inflight_bytes;
      cv_out.notify_all();
      if (!outbox.empty()) {
        lk.unlock();
        return start_write();
      }
      writing = false;
      const bool is_ended = end != End::none;
      lk.unlock();
      if (is_ended) wind_down();
    });
  }

  void wind_down() {
    if (!sock.is_open()) return;
    if (!linger_started) {
      linger_started = true;
      linger_timer.expires_after(std::clamp(opts.close_linger, Millis(0), kMaxWait));
      linger_timer.async_wait([this](error_code ec) {
        if (!ec) force_close();
      });
    }
    {
      std::lock_guard lk(m);
      if (writing) return;  // the write handler calls back when the queue is drained
    }
    if (!shutdown_sent) {
      shutdown_sent = true;
      error_code ignored;
      sock.shutdown(tcp::socket::shutdown_send, ignored);
    }
    if (peer_eof) return force_close();
    if (read_pending) return;  // its handler calls back
    read_pending = true;       // discard input until the peer closes
    wire.async_read_some(asio::buffer(discard_buf), [this](error_code ec, size_t) {
      read_pending = false;
      if (!sock.is_open()) return;
      if (ec) peer_eof = true;
      wind_down();
    });
  }

  void force_close() {
    error_code ignored;
    sock.close(ignored);
    linger_timer.cancel();
    std::lock_guard lk(m);
    outbox.clear();
    finished = true;
    cv_out.notify_all();
    cv_in.notify_all();
  }
};

Connection::Connection(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
Connection::Connection(Connection&&) noexcept = default;
Connection& Connection::operator=(Connection&& other) noexcept {
  if (this != &other) {
    if (impl_) impl_->stop();
    impl_ = std::move(other.impl_);
  }
  return *this;
}
Connection::~Connection() {
  if (impl_) impl_->stop();
}

Result<Connection> Connection::connect(const std::string& host, uint16_t port,
                                       Millis retry_timeout, ConnectionOptions options) {
  auto impl = std::make_unique<Impl>(std::move(options));
  const auto deadline = deadline_after(retry_timeout);
  std::string last_error = "timed out";
  for (;;) {
    error_code ec;
    tcp::resolver resolver(impl->io);
    auto endpoints = resolver.resolve(host, std::to_string(port), ec);
    if (ec) last_error = "cannot resolve " + host + ": " + ec.message();
    for (const auto& entry : endpoints) {
      if (remaining_until(deadline) == Millis(0)) break;
      error_code ignored, result = asio::error::timed_out;
      bool done = false;
      impl->sock.close(ignored);
      impl->sock.async_connect(entry.endpoint(), [&](error_code e) { result = e, done = true; });
      impl->io.restart();
      impl->io.run_for(remaining_until(deadline));
      if (!done) {
        impl->sock.close(ignored);
        impl->io.restart();
        impl->io.run();
        if (result == asio::error::operation_aborted) result = asio::error::timed_out;
      }
      if (!result) {
        impl->start();
        return Connection(std::move(impl));
      }
      last_error = result.message();
    }
    const Millis left = remaining_until(deadline);
    if (left == Millis(0)) break;
    std::this_thread::sleep_for(std::min(left, Millis(50)));
  }
  return Error{"cannot connect to " + host + ":" + std::to_string(port) + " within " +
               std::to_string(retry_timeout.count()) + " ms: " + last_error};
}

std::optional<std::string> Connection::send(const wire::Message& m) { return impl_->send(m); }
Received Connection::receive(Millis timeout) { return impl_->receive(timeout); }
void Connection::close(const std::string& reason) { impl_->close(reason); }
void Connection::close_with_error(const std::string& reason) { impl_->close_with_error(reason); }
const std::string& Connection::peer() const { return impl_->peer; }
bool Connection::encrypted() const { return impl_->tls.has_value(); }
bool Connection::accepted() const { return impl_->accepted; }

bool Connection::is_open() const {
  std::lock_guard lk(impl_->m);
  return impl_->end == Impl::End::none;
}

ConnectionStats Connection::stats() const {
  std::lock_guard lk(impl_->m);
  ConnectionStats s = impl_->stats;
  s.socket_bytes_sent = impl_->wire_out;
  s.socket_bytes_received = impl_->wire_in;
  return s;
}

// ---------------------------------------------------------------------------------------------
// Listener

struct Listener::Impl {
  asio::io_context io;
  tcp::acceptor acceptor{io};
  std::string address;
  uint16_t port = 0;
  uint64_t rejected = 0;

  std::string where() const { return address + ":" + std::to_string(port); }
};

Listener::Listener(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
Listener::Listener(Listener&&) noexcept = default;
Listener& Listener::operator=(Listener&&) noexcept = default;
Listener::~Listener() = default;

Result<Listener> Listener::open(uint16_t port, const std::string& address) {
  auto impl = std::make_unique<Impl>();
  error_code ec;
  const auto addr = asio::ip::make_address(address, ec);
  if (ec) return Error{"invalid listen address '" + address + "': " + ec.message()};
  const tcp::endpoint ep(addr, port);
  const std::string where = endpoint_string(ep);
  impl->acceptor.open(ep.protocol(), ec);
  if (!ec) impl->acceptor.set_option(tcp::acceptor::reuse_address(true), ec);
  if (!ec) impl->acceptor.bind(ep, ec);
  if (!ec) impl->acceptor.listen(asio::socket_base::max_listen_connections, ec);
  if (ec) return Error{"cannot listen on " + where + ": " + ec.message()};
  impl->address = addr.to_string();
  impl->port = impl->acceptor.local_endpoint(ec).port();
  if (ec) return Error{"cannot listen on " + where + ": " + ec.message()};
  return Listener(std::move(impl));
}

uint16_t Listener::port() const { return impl_->port; }
const std::string& Listener::address() const { return impl_->address; }
uint64_t Listener::rejected() const { return impl_->rejected; }

Result<Connection> Listener::accept(Millis timeout, ConnectionOptions options) {
  auto conn = std::make_unique<Connection::Impl>(std::move(options));
  error_code result;
  bool done = false;
  impl_->acceptor.async_accept(conn->sock, [&](error_code e) { result = e, done = true; });
  impl_->io.restart();
  impl_->io.run_for(std::clamp(timeout, Millis(0), kMaxWait));
  if (!done) {
    error_code ignored;
    impl_->acceptor.cancel(ignored);
    impl_->io.restart();
    impl_->io.run();
  }
  if (result == asio::error::operation_aborted)
    return Error{"no connection on " + impl_->where() + " within " + std::to_string(timeout.count()) + " ms",
                 ErrorKind::timeout};
  if (result) return Error{"accept on " + impl_->where() + ": " + result.message()};
  conn->accepted = true;
  conn->start();
  return Connection(std::move(conn));
}

Result<Peer> Listener::accept_peer(const wire::Hello& mine, const PeerExpectation& expect,
                                   Millis overall_timeout, Millis hello_timeout,
                                   ConnectionOptions options) {
  const auto deadline = deadline_after(overall_timeout);
  std::string last;
  for (Millis left; (left = remaining_until(deadline)) > Millis(0);) {
    auto conn = accept(left, options);
    if (!conn) {
      if (remaining_until(deadline) == Millis(0)) break;  // timed out
      return Error{conn.error()};
    }
    auto hello = handshake(*conn, mine, expect,
                           std::max(Millis(1), std::min(hello_timeout, remaining_until(deadline))));
    if (hello) return Peer{std::move(*conn), std::move(*hello)};
    ++impl_->rejected;
    last = hello.error();
  }
  return Error{"no valid peer on " + impl_->where() + " within " + std::to_string(overall_timeout.count()) + " ms (" +
                   std::to_string(impl_->rejected) + " rejected" + (last.empty() ? "" : "; last: " + last) + ")",
               ErrorKind::timeout};
}

}  // namespace occ::net
