#include "protocol/relay/relay.hpp"

#include <algorithm>
#include <deque>
#include <future>
#include <iostream>
#include <map>
#include <optional>
#include <random>
#include <thread>
#include <utility>
#include <vector>

#include "protocol/net/asio_names.hpp"

namespace occ::relay {
using namespace asio_names;

namespace {

constexpr size_t kMinChunk = 1500, kMaxChunk = 64 * 1024;
constexpr Millis kRetry{50};              // connect retry and accept-failure back-off
constexpr size_t kMaxControlLine = 256;   // a longer control line ends the control session

Clock::duration from_ms(double ms) {
  return std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double, std::milli>(ms));
}

// At most ~2 ms of transmission at the capped rate, so a capped stream flows smoothly.
size_t chunk_bytes(double rate_mbit) {
  if (rate_mbit <= 0) return kMaxChunk;
  return std::clamp(size_t(rate_mbit * 1e6 / 8 * 0.002), kMinChunk, kMaxChunk);
}

// splitmix64: independent jitter streams per (seed, connection, direction).
uint64_t mix(uint64_t x) {
  x += 0x9e3779b97f4a7c15ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}

std::string endpoint_string(const tcp::endpoint& ep) {
  return ep.address().to_string() + ":" + std::to_string(ep.port());
}

std::optional<std::string> open_acceptor(tcp::acceptor& a, const tcp::endpoint& ep) {
  error_code ec;
  a.open(ep.protocol(), ec);
  if (!ec) a.set_option(tcp::acceptor::reuse_address(true), ec);
  if (!ec) a.bind(ep, ec);
  if (!ec) a.listen(asio::socket_base::max_listen_connections, ec);
  if (ec) return "cannot listen on " + endpoint_string(ep) + ": " + ec.message();
  return std::nullopt;
}

struct Link;

// Everything below runs on the relay's io thread.
struct Hub {
  explicit Hub(RelayOptions o) : opts(std::move(o)) {}

  asio::io_context io;  // first member: destroyed last
  RelayOptions opts;
  tcp::acceptor acceptor{io}, control{io};
  asio::steady_timer accept_backoff{io};
  tcp::resolver::results_type target;
  std::string target_name;
  std::map<uint64_t, std::shared_ptr<Link>> links;  // open connections (connecting included)
  uint64_t accepted = 0, up_bytes = 0, down_bytes = 0;
  bool stalled = false;
  bool flip_down = false;  // "flip": invert one byte of the next chunk from the target

  void log(const std::string& line) const {
    if (opts.log)
      opts.log(line);
    else
      std::cerr << "occ_relay: " << line << std::endl;
  }
  void accept_next();
  void accept_control();
  std::string command(const std::string& line);
  void resume();
  size_t close_all(const std::string& why, bool abort);
  RelayStats stats() const;
};

// One direction of a connection: from -> queue (release times) -> to.
struct Pipe {
  struct Chunk {
    std::vector<uint8_t> bytes;
    Clock::time_point release;
  };

  Pipe(Link& link, tcp::socket& from, tcp::socket& to, std::string from_name, std::string to_name,
       const LinkParams& params, uint64_t seed, uint64_t& total)
      : link(link), from(from), to(to), from_name(std::move(from_name)), to_name(std::move(to_name)),
        params(params), rng(seed), total(total), inbuf(chunk_bytes(params.rate_mbit)), timer(from.get_executor()) {}

  Link& link;
  tcp::socket& from;
  tcp::socket& to;
  const std::string from_name, to_name;  // "client" / "target", for close reasons
  const LinkParams params;
  std::mt19937_64 rng;
  uint64_t& total;  // the hub's counter for this direction
  std::vector<uint8_t> inbuf;
  asio::steady_timer timer;  // waits for the head chunk's release
  std::deque<Chunk> queue;
  size_t queued = 0;       // bytes in queue (the head stays queued while being written)
  uint64_t forwarded = 0;  // bytes written
  Clock::time_point link_free{}, last_release{};
  bool reading = false, writing = false, eof = false, eof_forwarded = false;

  void read();
  void enqueue(size_t n);
  void write();
};

struct Link : std::enable_shared_from_this<Link> {
  Link(Hub& hub, uint64_t id, tcp::socket client_socket)
      : hub(hub), id(id), client(std::move(client_socket)), target(hub.io), retry(hub.io),
        up(*this, client, target, "client", "target", hub.opts.up, mix(hub.opts.seed ^ mix(2 * id)), hub.up_bytes),
        down(*this, target, client, "target", "client", hub.opts.down, mix(hub.opts.seed ^ mix(2 * id + 1)),
             hub.down_bytes) {}

  Hub& hub;
  const uint64_t id;
  tcp::socket client, target;
  asio::steady_timer retry;
  Clock::time_point connect_deadline;
  Pipe up, down;
  bool connected = false, closed = false;

  void connect();
  void on_connect(const error_code& ec);
  void pipe_finished();
  void close(const std::string& why, bool abort);
};

void Pipe::read() {
  if (reading || eof || link.closed || queued >= std::max<size_t>(link.hub.opts.max_queued_bytes, 1)) return;
  reading = true;
  from.async_read_some(asio::buffer(inbuf), [this, self = link.shared_from_this()](error_code ec, size_t n) {
    reading = false;
    if (link.closed) return;
    if (ec == asio::error::eof) {
      eof = true;
      write();
      return;
    }
    if (ec) return link.close(from_name + ": " + ec.message(), true);
    enqueue(n);
    write();
    read();
  });
}

void Pipe::enqueue(size_t n) {
  const auto now = Clock::now();
  const double transmit_ms = params.rate_mbit > 0 ? double(n) * 8 / (params.rate_mbit * 1e3) : 0;
  link_free = std::max(now, link_free) + from_ms(transmit_ms);
  double offset_ms = params.delay_ms;
  if (params.jitter_ms > 0) offset_ms += std::uniform_real_distribution<double>(-params.jitter_ms, params.jitter_ms)(rng);
  last_release = std::max(last_release, link_free + from_ms(std::max(0.0, offset_ms)));
  if (&to == &link.client && link.hub.flip_down) {  // tampering on the way, for integrity tests
    inbuf[n / 2] ^= 0x01;
    link.hub.flip_down = false;
  }
  queue.push_back({std::vector<uint8_t>(inbuf.begin(), inbuf.begin() + n), last_release});
  queued += n;
}

void Pipe::write() {
  if (writing || link.closed || link.hub.stalled) return;
  if (queue.empty()) {
    if (eof && !eof_forwarded) {
      eof_forwarded = true;
      error_code ignored;
      to.shutdown(tcp::socket::shutdown_send, ignored);
      link.pipe_finished();
    }
    return;
  }
  auto self = link.shared_from_this();
  if (queue.front().release > Clock::now()) {
    timer.expires_at(queue.front().release);  // cancels an earlier wait (its handler sees the error)
    timer.async_wait([this, self](error_code ec) {
      if (!ec && !link.closed) write();
    });
    return;
  }
  writing = true;
  asio::async_write(to, asio::buffer(queue.front().bytes), [this, self](error_code ec, size_t n) {
    writing = false;
    if (link.closed) return;
    if (ec) return link.close(to_name + ": " + ec.message(), true);
    queue.pop_front();
    queued -= n;
    forwarded += n;
    total += n;
    write();
    read();
  });
}

void Link::connect() {
  asio::async_connect(target, hub.target,
                      [self = shared_from_this()](error_code ec, const tcp::endpoint&) { self->on_connect(ec); });
}

void Link::on_connect(const error_code& ec) {
  if (closed) return;
  if (ec) {
    if (Clock::now() + kRetry > connect_deadline) return close("target unreachable: " + ec.message(), true);
    retry.expires_after(kRetry);
    retry.async_wait([self = shared_from_this()](error_code e) {
      if (!e && !self->closed) self->connect();
    });
    return;
  }
  error_code ignored;
  target.set_option(tcp::no_delay(true), ignored);
  connected = true;
  std::string peer = "?";
  if (auto ep = client.remote_endpoint(ignored); !ignored) peer = endpoint_string(ep);
  hub.log("conn " + std::to_string(id) + " open " + peer + " -> " + hub.target_name);
  up.read();
  down.read();
}

void Link::pipe_finished() {
  if (up.eof_forwarded && down.eof_forwarded) close("eof", false);
}

void Link::close(const std::string& why, bool abort) {
  if (closed) return;
  closed = true;
  // Logged first: the line is out before either peer can see the close.
  hub.log("conn " + std::to_string(id) + " closed (" + why + ") up " + std::to_string(up.forwarded) + " B down " +
          std::to_string(down.forwarded) + " B");
  for (tcp::socket* s : {&client, &target}) {
    error_code ignored;
    if (abort && s->is_open()) s->set_option(asio::socket_base::linger(true, 0), ignored);  // RST
    s->close(ignored);
  }
  retry.cancel();
  up.timer.cancel();
  down.timer.cancel();
  hub.links.erase(id);  // the caller's handler still holds a reference
}

void Hub::accept_next() {
  acceptor.async_accept([this](error_code ec, tcp::socket s) {
    if (!acceptor.is_open()) return;
    if (ec) {  // e.g. out of file descriptors: back off instead of spinning
      log("accept failed: " + ec.message());
      accept_backoff.expires_after(kRetry);
      accept_backoff.async_wait([this](error_code e) {
        if (!e) accept_next();
      });
      return;
    }
    error_code ignored;
    s.set_option(tcp::no_delay(true), ignored);
    auto link = std::make_shared<Link>(*this, ++accepted, std::move(s));
    links.emplace(link->id, link);
    link->connect_deadline = Clock::now() + opts.connect_timeout;
    link->connect();
    accept_next();
  });
}

// A control connection: one command line in, one answer line out, repeated.
struct ControlSession : std::enable_shared_from_this<ControlSession> {
  ControlSession(Hub& hub, tcp::socket s) : hub(hub), sock(std::move(s)), in(kMaxControlLine) {}
  Hub& hub;
  tcp::socket sock;
  asio::streambuf in;
  std::string answer;

  void next() {
    asio::async_read_until(sock, in, '\n', [self = shared_from_this()](error_code ec, size_t) {
      if (ec) return;  // EOF, an over-long line or the relay stopping: the session ends
      std::string line;
      std::istream is(&self->in);
      std::getline(is, line);  // consumes the newline; what follows stays for the next command
      while (!line.empty() && (line.back() == '\r' || line.back() == ' ')) line.pop_back();
      self->answer = self->hub.command(line) + "\n";
      asio::async_write(self->sock, asio::buffer(self->answer), [self](error_code e, size_t) {
        if (!e) self->next();
      });
    });
  }
};

void Hub::accept_control() {
  control.async_accept([this](error_code ec, tcp::socket s) {
    if (!control.is_open()) return;
    if (!ec) std::make_shared<ControlSession>(*this, std::move(s))->next();
    accept_control();
  });
}

std::string Hub::command(const std::string& line) {
  if (line == "stall") {
    stalled = true;
    return "ok stalled";
  }
  if (line == "resume") {
    resume();
    return "ok resumed";
  }
  if (line == "cut") return "ok cut " + std::to_string(close_all("cut", true));
  if (line == "flip") {
    flip_down = true;
    return "ok flip armed";
  }
  if (line == "stats") return stats().line();
  return "error: unknown command '" + line + "' (stall|resume|cut|flip|stats)";
}

void Hub::resume() {
  stalled = false;
  for (auto& [id, link] : links)
    if (link->connected) {
      link->up.write();
      link->down.write();
    }
}

size_t Hub::close_all(const std::string& why, bool abort) {
  std::vector<std::shared_ptr<Link>> open;
  for (auto& [id, link] : links) open.push_back(link);
  for (auto& link : open) link->close(why, abort);
  return open.size();
}

RelayStats Hub::stats() const {
  RelayStats s;
  s.up_bytes = up_bytes;
  s.down_bytes = down_bytes;
  for (auto& [id, link] : links) {
    s.queued_up += link->up.queued;
    s.queued_down += link->down.queued;
  }
  s.open = links.size();
  s.accepted = accepted;
  s.stalled = stalled;
  return s;
}

}  // namespace

std::string RelayStats::line() const {
  return "up=" + std::to_string(up_bytes) + " down=" + std::to_string(down_bytes) +
         " queued_up=" + std::to_string(queued_up) + " queued_down=" + std::to_string(queued_down) +
         " open=" + std::to_string(open) + " accepted=" + std::to_string(accepted) +
         " stalled=" + (stalled ? "1" : "0");
}

struct Relay::Impl {
  explicit Impl(RelayOptions o) : hub(std::move(o)) {}
  ~Impl() {
    if (!thread.joinable()) return;
    asio::post(hub.io, [this] {
      error_code ignored;
      hub.acceptor.close(ignored);
      hub.control.close(ignored);
      hub.accept_backoff.cancel();
      hub.close_all("relay stopped", false);
      hub.io.stop();  // control sessions are dropped with the io_context
    });
    thread.join();
  }

  // Runs f on the io thread and returns its result.
  template <class F>
  auto call(F f) {
    std::packaged_task<decltype(f())()> task(std::move(f));
    auto result = task.get_future();
    asio::post(hub.io, [&task] { task(); });
    return result.get();
  }

  Hub hub;
  std::thread thread;
  uint16_t port = 0, control_port = 0;
};

Result<Relay> Relay::start(RelayOptions options) {
  auto impl = std::make_unique<Impl>(std::move(options));
  Hub& hub = impl->hub;
  const RelayOptions& o = hub.opts;
  hub.target_name = o.target_host + ":" + std::to_string(o.target_port);
  error_code ec;
  hub.target = tcp::resolver(hub.io).resolve(o.target_host, std::to_string(o.target_port), ec);
  if (ec) return Error{"target " + hub.target_name + ": " + ec.message()};
  const auto address = asio::ip::make_address(o.listen_address, ec);
  if (ec) return Error{"listen address '" + o.listen_address + "': " + ec.message()};
  if (auto err = open_acceptor(hub.acceptor, {address, o.listen_port})) return Error{*err};
  impl->port = hub.acceptor.local_endpoint().port();
  hub.accept_next();
  if (o.control) {
    if (auto err = open_acceptor(hub.control, {asio::ip::address_v4::loopback(), 0})) return Error{"control: " + *err};
    impl->control_port = hub.control.local_endpoint().port();
    hub.accept_control();
  }
  impl->thread = std::thread([&hub] { hub.io.run(); });
  return Relay(std::move(impl));
}

Relay::Relay(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
Relay::Relay(Relay&&) noexcept = default;
Relay& Relay::operator=(Relay&&) noexcept = default;
Relay::~Relay() = default;

uint16_t Relay::port() const { return impl_->port; }
uint16_t Relay::control_port() const { return impl_->control_port; }

void Relay::stall() {
  impl_->call([this] { impl_->hub.stalled = true; });
}
void Relay::resume() {
  impl_->call([this] { impl_->hub.resume(); });
}
size_t Relay::cut() {
  return impl_->call([this] { return impl_->hub.close_all("cut", true); });
}
RelayStats Relay::stats() const {
  return impl_->call([this] { return impl_->hub.stats(); });
}

}  // namespace occ::relay
