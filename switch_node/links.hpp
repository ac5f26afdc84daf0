// A switch node's connections for one render client: the render client's, the link to the other
// node (node 1 connects to node 0; node 0 accepts it), the busy door, and what a resync or a
// restarted peer does to them. Node.cpp's schedule sends and receives through them; this owns
// who is connected.
//
// The door: while a client is served, the listener stays open and every connector gets
// Bye("busy: ...") in its handshake (after its hello and key were checked): a second render client
// learns at once that the cluster is busy, node 1 coming back early for the next client retries.
// The one exception: node 0 whose link to node 1 is down takes a restarted node 1 (rejoin); the
// render client's Resync then puts it back into the switch (relink).
// Threads: the session's thread calls everything; the door's thread reads the connections under
// a lock. Create one per render client (nothing carries over).
#pragma once
#include <atomic>
#include <chrono>
#include <memory>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "protocol/net/transport.hpp"
#include "switch_node/node.hpp"

namespace occ {

// A failure of this node's session: one "error:" line, the peers told why.
struct NodeFailure : std::runtime_error {
  using std::runtime_error::runtime_error;
};

class Links {
 public:
  // `listener`: the node's for its whole run (it outlives this).
  Links(const NodeOptions& o, const wire::Hello& mine, net::Listener& listener);
  ~Links();
  Links(const Links&) = delete;
  Links& operator=(const Links&) = delete;

  // Connects the session: node 1 connects to node 0, then accepts the render client; node 0
  // accepts both in whatever order they come. Then opens the door. Throws naming what is missing.
  void connect();
  // The end of the session: Byes to both peers (done, or failed).
  void close(bool failed);
  // Then: the door closed, a restarted node 1 waiting to rejoin told the render client is gone.
  void close_door();
  // Tells both peers this node failed (the session's error).
  void fail(const std::string& why);

  net::Connection& rvg() { return *rvg_; }
  const net::Connection& rvg() const { return *rvg_; }
  net::Connection* peer() { return peer_.get(); }  // null once dropped
  bool peer_open() const { return peer_ && peer_->is_open(); }
  const std::string& peer_addr() const { return peer_addr_; }
  uint64_t peer_sent_bytes() const;  // over every link to the other node in this session

  // Drops the link to the other node (it is gone or misbehaved), telling it why.
  void drop_peer(const std::string& why);
  // Node 0 without a working peer: takes a switch node 1 that came back through the door, at
  // most every 100 ms (it serves once the render client's Resync says so).
  void poll_for_peer();
  // The render client's Resync `r`: alone (nodes 1: the peer is dropped) or the switch again
  // (nodes 2: a fresh link unless the current one connected since the last resync: node 1
  // reconnects, node 0 waits up to --timeout-ms for the door to hand it the one that connects).
  void relink(const wire::Resync& r);

 private:
  class Door;
  net::PeerExpectation expect(std::optional<wire::Role> role, std::optional<uint8_t> node_id) const;
  std::optional<std::string> busy_reason(const wire::Hello& h);
  std::optional<std::string> door_reason(const wire::Hello& h);
  void hand_over_peer(net::Connection conn);
  std::unique_ptr<net::Connection> take_rejoined_peer();
  void set_peer(std::unique_ptr<net::Connection> c);
  net::Peer accept(const net::PeerExpectation& e, const std::string& what);
  void connect_peer();

  const NodeOptions& o_;
  const std::string who_, other_;
  const wire::Hello& mine_;
  net::Listener& listener_;  // during a session only the door uses it
  std::unique_ptr<net::Connection> peer_, rvg_;
  // peer_ (the pointer; the session thread writes it, the door reads it) and rejoined_peer_ (a
  // restarted node 1 the door let in, for the session to take).
  mutable std::mutex mu_;
  std::unique_ptr<net::Connection> rejoined_peer_;
  std::vector<std::unique_ptr<net::Connection>> dropped_;  // closing lingers: destroyed at the end
  std::string peer_addr_;
  bool peer_fresh_ = false;  // peer_ connected since the last resync
  std::chrono::steady_clock::time_point next_poll_;
  uint64_t dropped_sent_bytes_ = 0;
  std::unique_ptr<Door> door_;  // last: stopped first (it reads the connections above)
};

}  // namespace occ
