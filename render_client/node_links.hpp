// The render client's switch nodes as connections: the two of the switch (or one occlusion_server),
// the waits on them, the faults that drop a node (--on-node-failure) and the thread that takes a
// restarted node back (docs/recovery.md). What travels on them is FrameReceiver's.
#pragma once
#include <atomic>
#include <cstdint>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "protocol/net/transport.hpp"
#include "render_client/options.hpp"

namespace occ {

// The run ends (exit 1): --on-node-failure exit, or a node failed where nothing can take over.
struct ClientFailure : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// Switch node `node` failed (died, stalled past --timeout-ms, sent something invalid).
struct NodeFault : std::runtime_error {
  NodeFault(int n, const std::string& what) : std::runtime_error(what), node(n) {}
  int node;
};

class NodeLinks {
 public:
  explicit NodeLinks(const ClientOptions& o) : o_(o) {}
  ~NodeLinks() { stop_rejoiner(); }

  // Connects to every --connect address with `mine` (also what the rejoiner says); throws when a
  // node cannot be reached or refuses, or the addresses are not one pair / one node 0.
  void connect(const wire::Hello& mine);
  // Two switch nodes (not one occlusion_server).
  bool is_switch() const { return switch_; }
  bool up(int k) const { return bool(nodes_[k].conn); }
  net::Connection& conn(int k) { return *nodes_[k].conn; }
  // Its messages are stale until it echoes this Resync (0: none).
  uint32_t& await_epoch(int k) { return nodes_[k].await_epoch; }
  std::string node_name(int k) const;
  // The occlusion back end switch node k named in its Hello (its latest, after a rejoin); "" if none.
  const std::string& occlusion_backend(int k) const { return nodes_[k].occlusion_backend; }
  int members() const { return up(0) + up(1); }
  // The node serving frame `frame`: the switch's HC node, the one left, or none (-1).
  int server_of(uint32_t frame) const;

  // The next message from node `node` for frame `frame`, waiting up to --timeout-ms while the
  // other node's connection is watched. Throws NodeFault.
  net::Received receive_from(int node, uint32_t frame);
  // A failed node: with --on-node-failure exit the run ends here (ClientFailure). Otherwise the
  // node is closed, the next frame starts over without it (resync_needed) and the rejoiner
  // waits for it.
  void drop(int k, const std::string& what);
  // Nodes the rejoiner brought back since the last frame (then resync_needed).
  void take_rejoined(uint32_t frame);
  // Whether the nodes that are up start over at the next frame; taken by the resync.
  bool resync_needed() const { return need_resync_; }
  void resync_started() { need_resync_ = false; }
  // Stops the rejoiner and says goodbye (or that the render client failed) to every node.
  void close(bool failed);

 private:
  // One switch node as the client sees it.
  struct NodeLink {
    std::unique_ptr<net::Connection> conn;  // null: down (the rejoiner looks for it)
    std::string address;                    // its --connect
    std::string occlusion_backend;          // from its Hello
    uint32_t await_epoch = 0;
  };
  std::string end_of(int k);
  void want_rejoin(int k);
  void stop_rejoiner();
  void rejoin_loop();

  const ClientOptions& o_;
  wire::Hello mine_;
  NodeLink nodes_[2];
  std::vector<std::unique_ptr<net::Connection>> dropped_;  // destroyed at the end: closing lingers
  bool switch_ = false;
  bool need_resync_ = false;
  // The rejoiner thread (rejoin_loop) and what it shares with the renderer thread.
  std::thread rejoiner_;
  std::atomic<bool> stop_rejoin_{false};
  std::mutex rejoin_mu_;
  bool wanted_[2] = {false, false};
  std::unique_ptr<net::Connection> rejoined_[2];
  std::string rejoined_backend_[2];  // the rejoined node's Hello.occlusion_backend
};

}  // namespace occ
