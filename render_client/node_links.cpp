#include "render_client/node_links.hpp"

#include <algorithm>
#include <chrono>
#include <iostream>

#include "common/error.hpp"
#include "protocol/cluster/switch_step.hpp"

namespace occ {

namespace {

using Clock = std::chrono::steady_clock;
using net::Millis;

// How often a client waiting for one switch node looks at the other node's connection.
constexpr Millis kWatchOther{20};

}  // namespace

void NodeLinks::connect(const wire::Hello& mine) {
  mine_ = mine;
  for (const std::string& text : o_.connect) {
    const net::Endpoint e = net::parse_endpoint("connect", text);
    net::PeerExpectation expect{wire::Role::switch_node, std::nullopt};
    expect.key = o_.key ? &*o_.key : nullptr;
    auto conn = net::Connection::connect(e.host, e.port, Millis(o_.timeout_ms), net::keyed_options(expect.key));
    if (!conn) throw std::runtime_error("cannot reach switch node at " + text + ": " + conn.error());
    auto hello = net::handshake(*conn, mine_, expect, Millis(o_.timeout_ms));
    if (!hello && hello.error_kind() == ErrorKind::busy)
      throw std::runtime_error("the cluster is busy: the switch node at " + text + " refused us: " + hello.error());
    if (!hello) throw std::runtime_error(hello.error());
    NodeLink& slot = nodes_[hello->node_id & 1];
    if (slot.conn) throw InputError("--connect: both addresses are switch node " + std::to_string(hello->node_id));
    slot.conn = std::make_unique<net::Connection>(std::move(*conn));
    slot.address = text;
    slot.occlusion_backend = hello->occlusion_backend;
  }
  if (!nodes_[0].conn) throw InputError("--connect: a single server must be node 0 (an occlusion_server)");
  switch_ = bool(nodes_[1].conn);
  std::cerr << "render_client: connected to switch node 0 (" << nodes_[0].conn->peer() << ")"
            << (switch_ ? " and 1 (" + nodes_[1].conn->peer() + ")" : std::string(" only")) << "\n";
}

std::string NodeLinks::node_name(int k) const {
  return "switch node " + std::to_string(k) + " (" + (nodes_[k].conn ? nodes_[k].conn->peer() : nodes_[k].address) + ")";
}

int NodeLinks::server_of(uint32_t frame) const {
  if (up(0) && up(1)) return int(hc_node_of_frame(frame));
  return up(0) ? 0 : up(1) ? 1 : -1;
}

// Meanwhile the other node's connection is watched: when it ends (the node died: reset or EOF,
// or it said Bye), the other node is dropped at once (NodeFault for it), without waiting out the
// timeout. The node waited for may be waiting for the dead one itself: a node killed between
// queuing its last frame to this client and to its peer leaves that frame complete here but not
// on the peer, which then drops its peer and waits for this client's resync, while this client
// waited for the peer's next frame; both waited out --timeout-ms and the client dropped the
// healthy node too.
net::Received NodeLinks::receive_from(int node, uint32_t frame) {
  const Clock::time_point deadline = Clock::now() + Millis(o_.timeout_ms);
  const int other = 1 - node;
  net::Received r;
  for (;;) {
    const Millis left = std::max(Millis(0), std::chrono::duration_cast<Millis>(deadline - Clock::now()));
    r = nodes_[node].conn->receive(std::min(left, kWatchOther));
    if (r.status != net::Received::Status::timeout || left <= kWatchOther) break;
    if (nodes_[other].conn && !nodes_[other].conn->is_open())
      throw NodeFault(other, "frame " + std::to_string(frame) + ": " + node_name(other) + " " + end_of(other) +
                                 " (noticed while waiting for " + node_name(node) + ")");
  }
  if (r.ok()) return r;
  std::string what = r.status == net::Received::Status::timeout
                         ? "sent nothing for " + std::to_string(o_.timeout_ms) + " ms"
                         : (r.status == net::Received::Status::closed ? "closed the connection: " : "failed: ") + r.reason;
  throw NodeFault(node, "frame " + std::to_string(frame) + ": " + node_name(node) + " " + what);
}

// Why switch node k's connection ended (it has): its unread messages are discarded (it is dropped).
std::string NodeLinks::end_of(int k) {
  for (;;) {
    net::Received r = nodes_[k].conn->receive(Millis(0));
    if (r.ok()) continue;
    if (r.status == net::Received::Status::closed) return "closed the connection: " + r.reason;
    return "failed: " + (r.status == net::Received::Status::error ? r.reason : std::string("connection ended"));
  }
}

void NodeLinks::drop(int k, const std::string& what) {
  if (!o_.degrade) throw ClientFailure(what);
  nodes_[k].conn->close_with_error("render client dropped switch node " + std::to_string(k) + ": " + what);
  dropped_.push_back(std::move(nodes_[k].conn));  // destroyed at the end: closing lingers up to 1.5 s
  nodes_[k].await_epoch = 0;
  need_resync_ = true;
  const int other = 1 - k;
  std::cerr << "render_client: " << what << ": degraded: "
            << (switch_ && nodes_[other].conn ? node_name(other) + " serves alone until it is back"
                : switch_ ? std::string("frustum culling in the render client until a node is back")
                          : std::string("frustum culling in the render client to the end (an occlusion_server is not "
                                        "taken back)"))
            << "\n";
  if (switch_) want_rejoin(k);
}

// ---- rejoin: a thread tries the dropped node's address until a restarted node answers the
// hello (same scene and settings, node id), and hands the connection over; the next frame
// starts with a resync.
void NodeLinks::want_rejoin(int k) {
  {
    std::lock_guard<std::mutex> lock(rejoin_mu_);
    wanted_[k] = true;
  }
  if (!rejoiner_.joinable()) rejoiner_ = std::thread([this] { rejoin_loop(); });
}

void NodeLinks::rejoin_loop() {
  Clock::time_point next_try[2] = {Clock::now(), Clock::now()};
  Millis backoff[2] = {Millis(200), Millis(200)};
  while (!stop_rejoin_) {
    std::this_thread::sleep_for(Millis(20));
    for (int k = 0; k < 2 && !stop_rejoin_; ++k) {
      std::string address;
      {
        std::lock_guard<std::mutex> lock(rejoin_mu_);
        if (!wanted_[k] || Clock::now() < next_try[k]) continue;
        address = nodes_[k].address;
      }
      next_try[k] = Clock::now() + Millis(200);
      const net::Endpoint e = net::parse_endpoint("connect", address);
      net::PeerExpectation expect{wire::Role::switch_node, uint8_t(k)};
      expect.key = o_.key ? &*o_.key : nullptr;  // a keyed cluster takes back only a node with the key
      auto conn = net::Connection::connect(e.host, e.port, Millis(20), net::keyed_options(expect.key));
      if (!conn) continue;  // nothing listens there (yet)
      auto hello = net::handshake(*conn, mine_, expect, Millis(std::min(o_.timeout_ms, 5000)));
      if (!hello) {  // logged by the connection; a stranger there is not asked again at once
        next_try[k] = Clock::now() + backoff[k];
        backoff[k] = std::min(backoff[k] * 2, Millis(5000));
        continue;
      }
      std::lock_guard<std::mutex> lock(rejoin_mu_);
      rejoined_[k] = std::make_unique<net::Connection>(std::move(*conn));
      rejoined_backend_[k] = hello->occlusion_backend;
      wanted_[k] = false;
      backoff[k] = Millis(200);
    }
  }
}

void NodeLinks::stop_rejoiner() {
  stop_rejoin_ = true;
  if (rejoiner_.joinable()) rejoiner_.join();
}

void NodeLinks::take_rejoined(uint32_t frame) {
  std::lock_guard<std::mutex> lock(rejoin_mu_);
  for (int k = 0; k < 2; ++k) {
    if (!rejoined_[k]) continue;
    nodes_[k].conn = std::move(rejoined_[k]);
    nodes_[k].occlusion_backend = rejoined_backend_[k];
    std::cerr << "render_client: frame " << frame << ": " << node_name(k) << " is back\n";
    need_resync_ = true;
  }
}

void NodeLinks::close(bool failed) {
  stop_rejoiner();
  for (auto& c : rejoined_)
    if (c) c->close("render client done");
  for (auto& n : nodes_)
    if (n.conn) failed ? n.conn->close_with_error("render client failed") : n.conn->close("render client done");
}

}  // namespace occ
