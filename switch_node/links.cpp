#include "switch_node/links.hpp"

#include <chrono>
#include <iostream>

namespace occ {

using Clock = std::chrono::steady_clock;
using net::Millis;

// Refuses (and logs) every connector but a restarted node 1 that door_reason() lets in.
class Links::Door {
 public:
  explicit Door(Links& links) : thread_([this, &links] {
    net::PeerExpectation e = links.expect(std::nullopt, std::nullopt);
    e.refuse = [&links](const wire::Hello& h) { return links.door_reason(h); };
    while (!stop_) {
      auto conn = links.listener_.accept(Millis(100), net::keyed_options(e.key));
      if (!conn) continue;
      if (auto hello = net::handshake(*conn, links.mine_, e, Millis(2000))) links.hand_over_peer(std::move(*conn));
    }
  }) {}
  ~Door() {
    stop_ = true;
    thread_.join();
  }

 private:
  std::atomic<bool> stop_{false};
  std::thread thread_;  // last: started once stop_ exists
};

Links::Links(const NodeOptions& o, const wire::Hello& mine, net::Listener& listener)
    : o_(o),
      who_("switch_node " + std::to_string(o.id)),
      other_("switch node " + std::to_string(1 - o.id)),
      mine_(mine),
      listener_(listener) {}

Links::~Links() { door_.reset(); }

net::PeerExpectation Links::expect(std::optional<wire::Role> role, std::optional<uint8_t> node_id) const {
  net::PeerExpectation e{role, node_id};
  e.key = o_.key ? &*o_.key : nullptr;
  return e;
}

// Why this node turns away a connector whose slot is taken (nullopt: it may have the slot).
std::optional<std::string> Links::busy_reason(const wire::Hello& h) {
  const bool is_node1 = o_.id == 0 && h.role == wire::Role::switch_node && h.node_id == 1;
  const bool is_rvg = h.role == wire::Role::render_client;
  if (!is_node1 && !is_rvg)
    return "unexpected peer: " + std::string(wire::role_name(h.role)) + " " + std::to_string(h.node_id);
  std::lock_guard<std::mutex> lock(mu_);  // peer_ changes during a session (rejoin)
  const auto& slot = is_node1 ? peer_ : rvg_;
  if (!slot || !slot->is_open()) return std::nullopt;
  return std::string(wire::kByeBusy) + who_ + " is serving " +
         (is_rvg ? "another render client (" + rvg_->peer() + ")" : "switch node 1 (" + peer_->peer() + ")") +
         "; try again when it has finished";
}

// What the door says to a connector during a session; nullopt only for a switch node 1 coming
// back (restarted) to node 0 while node 0's link to its peer is down.
std::optional<std::string> Links::door_reason(const wire::Hello& h) {
  if (o_.id == 0 && h.role == wire::Role::switch_node && h.node_id == 1) {
    std::lock_guard<std::mutex> lock(mu_);
    if (!peer_ || !peer_->is_open()) {
      if (!rejoined_peer_ || !rejoined_peer_->is_open()) return std::nullopt;
      return std::string(wire::kByeBusy) + who_ + ": a restarted switch node 1 (" + rejoined_peer_->peer() +
             ") is already waiting to rejoin";
    }
  }
  auto why = busy_reason(h);
  return why ? why
             : std::optional<std::string>(std::string(wire::kByeBusy) + who_ +
                                          " is serving a render client; try again when it has finished");
}

// The door's handshake passed: a restarted switch node 1 (door_reason); the session takes it.
void Links::hand_over_peer(net::Connection conn) {
  auto c = std::make_unique<net::Connection>(std::move(conn));
  std::cerr << who_ << ": " << other_ << " (" << c->peer() << ") is back; waiting for the render client's resync\n";
  std::unique_ptr<net::Connection> stale;
  std::lock_guard<std::mutex> lock(mu_);
  stale = std::move(rejoined_peer_);  // closed (door_reason): destroyed after the lock
  rejoined_peer_ = std::move(c);
}

std::unique_ptr<net::Connection> Links::take_rejoined_peer() {
  std::lock_guard<std::mutex> lock(mu_);
  return std::move(rejoined_peer_);
}

// peer_ is written only by the session thread; the door reads it under mu_.
void Links::set_peer(std::unique_ptr<net::Connection> c) {
  std::unique_ptr<net::Connection> old;
  std::lock_guard<std::mutex> lock(mu_);
  old = std::move(peer_);
  peer_ = std::move(c);
  if (old) dropped_.push_back(std::move(old));  // destroyed at the end: closing lingers up to 1.5 s
}

// Waits for a peer on the listener: for --timeout-ms, or (--serve) as long as it takes.
net::Peer Links::accept(const net::PeerExpectation& e, const std::string& what) {
  for (;;) {
    auto p = listener_.accept_peer(mine_, e, Millis(o_.timeout_ms), Millis(2000), net::keyed_options(e.key));
    if (p) return std::move(*p);
    if (!o_.serve) throw std::runtime_error(who_ + ": " + what + ": " + p.error());
    if (p.error_kind() != ErrorKind::timeout) {  // not a timeout: do not spin
      std::cerr << who_ << ": " << what << ": " << p.error() << "\n";
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
  }
}

// Node 1: the link to node 0 (at start, and when a resync asks for the switch again). Node 0
// may still be finishing its last client (--serve), or not have noticed yet that its old link is
// gone: it says "busy" until then, and this retries for --timeout-ms.
void Links::connect_peer() {
  const Millis timeout(o_.timeout_ms);
  const net::Endpoint pe = net::parse_endpoint("peer", o_.peer);
  const auto deadline = Clock::now() + timeout;
  for (;;) {
    auto conn = net::Connection::connect(pe.host, pe.port, timeout, net::keyed_options(o_.key ? &*o_.key : nullptr));
    if (!conn) throw std::runtime_error(who_ + ": cannot reach switch node 0 at " + o_.peer + ": " + conn.error());
    auto hello = net::handshake(*conn, mine_, expect(wire::Role::switch_node, uint8_t(0)), timeout);
    if (hello) {
      set_peer(std::make_unique<net::Connection>(std::move(*conn)));
      peer_fresh_ = true;
      peer_addr_ = peer_->peer();
      return;
    }
    if (hello.error_kind() != ErrorKind::busy || Clock::now() > deadline)
      throw std::runtime_error(who_ + ": " + hello.error());
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
}

void Links::connect() {
  if (o_.id == 1) {
    connect_peer();
    net::Peer rvg = accept(expect(wire::Role::render_client, std::nullopt), "no render client");
    rvg_ = std::make_unique<net::Connection>(std::move(rvg.connection));
    if (!peer_->is_open()) {  // node 0 went away while this node waited for the client (--serve)
      std::cerr << who_ << ": the link to switch node 0 ended while waiting for the render client; reconnecting\n";
      connect_peer();
    }
  } else {
    // Node 0 accepts both the render client and switch node 1, in whatever order they come; a
    // second of either (while the first is connected) is refused in the handshake.
    net::PeerExpectation e = expect(std::nullopt, std::nullopt);
    e.refuse = [this](const wire::Hello& h) { return busy_reason(h); };
    while (!peer_ || !rvg_ || !peer_->is_open() || !rvg_->is_open()) {
      net::Peer p = accept(e, "waiting for peers");
      auto c = std::make_unique<net::Connection>(std::move(p.connection));
      if (p.hello.role == wire::Role::switch_node)
        set_peer(std::move(c));
      else
        rvg_ = std::move(c);
    }
    peer_fresh_ = true;
  }
  peer_addr_ = peer_->peer();
  std::cerr << who_ << ": connected: peer " << peer_->peer() << ", render client " << rvg_->peer() << "\n";
  door_ = std::make_unique<Door>(*this);  // from now on, a second render client is told the cluster is busy
}

void Links::fail(const std::string& why) {
  if (peer_) peer_->close_with_error(why);
  if (rvg_) rvg_->close_with_error(why);
}

void Links::close(bool failed) {
  if (!failed && peer_) peer_->close(wire::kByeDone);
  if (rvg_) rvg_->close(failed ? "failed" : wire::kByeDone);
}

void Links::close_door() {
  door_.reset();
  std::lock_guard<std::mutex> lock(mu_);
  if (rejoined_peer_) rejoined_peer_->close_with_error(who_ + ": the render client is gone");
}

uint64_t Links::peer_sent_bytes() const { return dropped_sent_bytes_ + (peer_ ? peer_->stats().sent.bytes : 0); }

void Links::drop_peer(const std::string& why) {
  if (!peer_) return;
  dropped_sent_bytes_ += peer_->stats().sent.bytes;
  peer_->close_with_error(why);
  set_peer(nullptr);
}

void Links::poll_for_peer() {
  if (o_.id != 0 || peer_open()) return;
  const Clock::time_point now = Clock::now();
  if (now < next_poll_) return;
  next_poll_ = now + std::chrono::milliseconds(100);
  std::unique_ptr<net::Connection> c = take_rejoined_peer();
  if (!c) return;
  drop_peer("replaced");
  set_peer(std::move(c));
  peer_fresh_ = true;
  peer_addr_ = peer_->peer();
}

void Links::relink(const wire::Resync& r) {
  if (r.nodes == 1) {
    drop_peer("the render client dropped " + other_ + " (" + who_ + " serves alone from frame " +
              std::to_string(r.frame) + ")");
  } else if (!peer_open() || !peer_fresh_) {
    drop_peer("resync at frame " + std::to_string(r.frame) + ": a new connection to " + other_);
    if (o_.id == 1) {
      connect_peer();
    } else {  // the door hands over the node 1 that connects
      const Clock::time_point deadline = Clock::now() + Millis(o_.timeout_ms);
      std::unique_ptr<net::Connection> c;
      while (!(c = take_rejoined_peer())) {
        if (Clock::now() >= deadline)
          throw NodeFailure("resync at frame " + std::to_string(r.frame) + ": no " + other_ + " within " +
                            std::to_string(o_.timeout_ms) + " ms");
        std::this_thread::sleep_for(std::chrono::milliseconds(10));
      }
      set_peer(std::move(c));
      peer_addr_ = peer_->peer();
    }
  }
  peer_fresh_ = false;
}

}  // namespace occ
