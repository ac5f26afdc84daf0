#include "switch_node/node.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <mutex>
#include <optional>
#include <cstdio>
#include <iostream>
#include <thread>

#include "common/camera_buffer.hpp"
#include "common/cpu_time.hpp"
#include "common/culling.hpp"
#include "common/error.hpp"
#include "common/gl/hzb_query.hpp"
#include "common/gl/scene_renderer.hpp"
#include "common/gl/startup.hpp"
#include "common/hash.hpp"
#include "common/memory.hpp"
#include "protocol/cluster/camera_receiver.hpp"
#include "protocol/cluster/switch_step.hpp"
#include "protocol/net/transport.hpp"
#include "protocol/visible_set.hpp"

namespace occ {

namespace {

using Clock = std::chrono::steady_clock;
using net::Millis;

uint32_t micros_since(Clock::time_point t0) {
  return uint32_t(std::chrono::duration_cast<std::chrono::microseconds>(Clock::now() - t0).count());
}

struct NodeFailure : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// The render client sent a Resync (camera_receiver.hpp): the current run of frames stops where it
// is waiting and the loop starts over as the Resync says.
struct Interrupted {};

class SwitchNode {
 public:
  explicit SwitchNode(const NodeOptions& o)
      : o_(o), who_("switch_node " + std::to_string(o.id)), other_("switch node " + std::to_string(1 - o.id)) {}

  int run() {
    g_ = start_scene_gl(who_, o_.scene, o_.config.lod(), o_.gl, o_.width, o_.height);
    g_.renderer->set_occluder_offset(true);  // OR occluders must not hide their own query boxes
    mine_ = make_hello(wire::Role::switch_node, uint8_t(o_.id), {o_.width, o_.height}, g_.fingerprint(),
                       g_.hierarchy().params(), o_.config, who_);
    // Both nodes keep their listener for the whole run: node 0 takes a restarted node 1 through it
    // (the Door hands it over), and it tells a second render client the cluster is busy.
    listener_.emplace(open_listener(who_, o_.listen));
    if (!o_.serve) return session();
    // --serve: one render client after the other, each in a session of its own (both nodes
    // start it from scratch: new connections, including the link between the nodes, and fresh
    // per-client state), until --sessions clients have been served (0: forever).
    int failed = 0;
    for (int n = 1;; ++n) {
      const int code = session();
      failed += code != 0;
      if (o_.sessions > 0 && n >= o_.sessions) {
        std::cerr << who_ << ": served " << n << " render clients (" << failed << " failed), as --sessions asked\n";
        return failed ? 1 : 0;
      }
      std::cerr << who_ << ": render client " << n << (code ? " failed" : " done")
                << "; waiting for the next one (--serve)\n";
    }
  }

 private:
  // One render client, from the connections to the summary. Returns 0 after the client's Bye.
  int session() {
    reset_client_state();
    connect();
    door_.start(*this);  // from now on, a second render client is told the cluster is busy
    cameras_in_.emplace(*rvg_, *cameras_, Viewport{o_.width, o_.height});
    int code = 0;
    try {
      loop();
    } catch (const std::exception& e) {  // NodeFailure, or a bug/resource error: same clean shutdown
      // A frame in flight when the render client finished (latest mode) is not a failure: wait
      // for its goodbye a little before calling it one.
      for (int i = 0; i < 300 && !rvg_->is_open() && !cameras_in_->done(); ++i)
        std::this_thread::sleep_for(std::chrono::milliseconds(10));
      if (!cameras_in_->client_said_bye()) {
        std::cerr << "error: " << who_ << ": " << e.what() << "\n";
        code = 1;
        if (peer_) peer_->close_with_error(who_ + " failed: " + e.what());
        rvg_->close_with_error(who_ + " failed: " + e.what());
      } else {
        std::cerr << who_ << ": stopped: " << e.what() << " (after the " << cameras_in_->end_reason() << ")\n";
      }
    }
    if (code == 0 && peer_) peer_->close(wire::kByeDone);
    rvg_->close(code ? "failed" : wire::kByeDone);
    cameras_in_->join();
    door_.stop();
    {
      std::lock_guard<std::mutex> lock(link_mu_);
      if (rejoined_peer_) rejoined_peer_->close_with_error(who_ + ": the render client is gone");
    }
    print_summary();
    return code;
  }

  // Everything that belongs to one render client starts afresh: connections, cameras, sets and
  // diff streams, the query history of adaptive queries, the visibility hold, statistics.
  void reset_client_state() {
    cameras_in_.reset();
    set_peer(nullptr);
    rvg_.reset();
    {
      std::lock_guard<std::mutex> lock(link_mu_);
      rejoined_peer_.reset();
    }
    dropped_.clear();
    cameras_.emplace();
    skipper_.reset();
    hold_.reset();
    if (o_.hc.adaptive_queries) skipper_.emplace(g_.hierarchy().size());
    if (o_.hc.visibility_hold > 0) hold_.emplace(g_.hierarchy().size(), uint32_t(o_.hc.visibility_hold));
    step_.emplace(*g_.renderables, o_.config, o_.height);
    querier_.reset();
    // Sample counts only matter to visible-pixel LOD (a node with fewer than tau samples stops).
    querier_ = std::make_unique<HcQuerier>(*g_.ctx, o_.hc.test, o_.config.visible_pixel_lod && o_.config.lod());
    visible_ = VisibleSet(g_.renderables->count());
    stream_ = DiffReceiver{};
    last_camera_.reset();
    peer_addr_.clear();
    peer_fresh_ = single_ = false;
    peer_lost_.clear();
    peer_epoch_wait_ = peer_resync_seen_ = 0;
    next_poll_ = Clock::time_point{};
    peer_sent_bytes_ = resyncs_ = single_frames_ = 0;
    tail_cpu0_ = hc_cpu0_ = 0;
    or_us_ = or_cpu_us_ = or_tail_cpu_us_ = or_tail_us_ = 0;
    frames_ = queries_ = skipped_ = pixel_stops_ = hlods_ = assumed_visible_ = held_ = 0;
  }

  net::PeerExpectation expect(std::optional<wire::Role> role, std::optional<uint8_t> node_id) const {
    net::PeerExpectation e{role, node_id};
    e.key = o_.key ? &*o_.key : nullptr;
    return e;
  }

  // Why this node turns away a connector whose slot is taken (nullopt: it may have the slot).
  std::optional<std::string> busy_reason(const wire::Hello& h) {
    const bool is_node1 = o_.id == 0 && h.role == wire::Role::switch_node && h.node_id == 1;
    const bool is_rvg = h.role == wire::Role::render_client;
    if (!is_node1 && !is_rvg)
      return "unexpected peer: " + std::string(wire::role_name(h.role)) + " " + std::to_string(h.node_id);
    std::lock_guard<std::mutex> lock(link_mu_);  // peer_ changes during a session (rejoin)
    const auto& slot = is_node1 ? peer_ : rvg_;
    if (!slot || !slot->is_open()) return std::nullopt;
    return std::string(wire::kByeBusy) + who_ + " is serving " +
           (is_rvg ? "another render client (" + rvg_->peer() + ")" : "switch node 1 (" + peer_->peer() + ")") +
           "; try again when it has finished";
  }

  // What the Door says to a connector during a session; nullopt only for a switch node 1 coming
  // back (restarted) to node 0 while node 0's link to its peer is down: the session takes it over
  // (poll_for_peer, follow) and the render client's Resync puts it back into the switch.
  std::optional<std::string> door_reason(const wire::Hello& h) {
    if (o_.id == 0 && h.role == wire::Role::switch_node && h.node_id == 1) {
      std::lock_guard<std::mutex> lock(link_mu_);
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

  // The Door's handshake passed: a restarted switch node 1 (door_reason); the session takes it.
  void hand_over_peer(net::Connection conn) {
    auto c = std::make_unique<net::Connection>(std::move(conn));
    std::cerr << who_ << ": " << other_ << " (" << c->peer() << ") is back; waiting for the render client's resync\n";
    std::unique_ptr<net::Connection> stale;
    std::lock_guard<std::mutex> lock(link_mu_);
    stale = std::move(rejoined_peer_);  // closed (door_reason): destroyed after the lock
    rejoined_peer_ = std::move(c);
  }

  std::unique_ptr<net::Connection> take_rejoined_peer() {
    std::lock_guard<std::mutex> lock(link_mu_);
    return std::move(rejoined_peer_);
  }

  // peer_ is written only by the session thread; the Door reads it under link_mu_.
  void set_peer(std::unique_ptr<net::Connection> c) {
    std::unique_ptr<net::Connection> old;
    std::lock_guard<std::mutex> lock(link_mu_);
    old = std::move(peer_);
    peer_ = std::move(c);
    if (old) dropped_.push_back(std::move(old));  // destroyed at the end: closing lingers up to 1.5 s
  }

  // Waits for a peer on the listener: for --timeout-ms, or (--serve) as long as it takes.
  net::Peer accept(const net::PeerExpectation& e, const std::string& what) {
    for (;;) {
      auto p = listener_->accept_peer(mine_, e, Millis(o_.timeout_ms));
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
  void connect_peer() {
    const Millis timeout(o_.timeout_ms);
    const net::Endpoint pe = net::parse_endpoint("peer", o_.peer);
    const auto deadline = Clock::now() + timeout;
    for (;;) {
      auto conn = net::Connection::connect(pe.host, pe.port, timeout);
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

  void connect() {
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
  }

  // While a client is served, the listener stays open and every connector gets Bye("busy: ...")
  // in its handshake (after its hello and key were checked): a second render client learns at
  // once that the cluster is busy, node 1 coming back early for the next client retries. The one
  // exception (door_reason): node 0 whose link to node 1 is down takes a restarted node 1.
  class Door {
   public:
    ~Door() { stop(); }
    void start(SwitchNode& node) {
      stop();
      stop_ = false;
      thread_ = std::thread([this, &node] {
        net::PeerExpectation e = node.expect(std::nullopt, std::nullopt);
        e.refuse = [&node](const wire::Hello& h) { return node.door_reason(h); };
        while (!stop_) {
          auto conn = node.listener_->accept(Millis(100));
          if (!conn) continue;
          // Refused (and logged) unless door_reason let a restarted node 1 in.
          if (auto hello = net::handshake(*conn, node.mine_, e, Millis(2000)))
            node.hand_over_peer(std::move(*conn));
        }
      });
    }
    void stop() {
      stop_ = true;
      if (thread_.joinable()) thread_.join();
    }

   private:
    std::atomic<bool> stop_{false};
    std::thread thread_;
  };

  // Node 0 without a working peer: takes a switch node 1 that came back through the Door (a
  // restarted node 1 connects to node 0 before it accepts the render client), at most every
  // 100 ms. It serves once the render client's Resync says so.
  void poll_for_peer() {
    if (o_.id != 0 || (peer_ && peer_->is_open())) return;
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

  void drop_peer(const std::string& why) {
    if (!peer_) return;
    const auto st = peer_->stats();
    peer_sent_bytes_ += st.sent.bytes;
    peer_->close_with_error(why);
    set_peer(nullptr);
  }

  // The render client's instruction: start over at r.frame with empty sets, as the switch (2) or
  // alone (1). Answers with the same Resync once ready.
  wire::Resync follow(const wire::Resync& r) {
    ++resyncs_;
    visible_.clear();
    stream_ = DiffReceiver{};
    last_camera_.reset();
    peer_lost_.clear();
    // The visibility hold starts over too: on both nodes (a restarted one has no history) as at frame 0.
    if (o_.hc.visibility_hold > 0) hold_.emplace(g_.hierarchy().size(), uint32_t(o_.hc.visibility_hold));
    if (r.nodes == 1) {
      drop_peer("the render client dropped " + other_ + " (" + who_ + " serves alone from frame " +
                std::to_string(r.frame) + ")");
    } else if (!peer_ || !peer_->is_open() || !peer_fresh_) {
      drop_peer("resync at frame " + std::to_string(r.frame) + ": a new connection to " + other_);
      if (o_.id == 1) {
        connect_peer();
      } else {  // the Door hands over the node 1 that connects
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
    // The switch again: the same Resync on the link marks where this node's new run starts (the
    // other node skips what came before it, next_from_peer), and this node skips what the other
    // sent before its own marker (unless that marker was already read).
    peer_epoch_wait_ = 0;
    if (r.nodes == 2) {
      peer_epoch_wait_ = peer_resync_seen_ == r.epoch ? 0 : r.epoch;
      if (auto err = peer_->send(r)) peer_lost_ = "frame " + std::to_string(r.frame) + ": the resync marker: " + *err;
    }
    peer_resync_seen_ = 0;
    std::cerr << who_ << ": resync at frame " << r.frame << " (render client's resync " << r.epoch << "): "
              << (r.nodes == 2 ? "the switch with " + other_ + " (" + peer_addr_ + ")" : std::string("serving alone"))
              << ", from empty visible sets\n";
    if (auto err = rvg_->send(r)) throw NodeFailure("resync at frame " + std::to_string(r.frame) + ": " + *err);
    return r;
  }

  void loop() {
    wire::Resync start{0, 0, 2};  // the implicit first instruction: the switch from frame 0
    for (;;) {
      try {
        if (start.nodes == 2)
          run_switch(start.frame);
        else
          run_single(start.frame);
        return;  // the render client is done
      } catch (const Interrupted&) {
        start = follow(*cameras_in_->take_resync());
      }
    }
  }

  // The camera of `frame` (lockstep) or the newest from `min_camera` on (latest); nullopt when the
  // render client is done. Waits up to twice --timeout-ms: the render client may itself be waiting
  // out its timeout on the other node before it drops that one and sends this one a Resync.
  std::optional<NumberedCamera> take_camera(uint32_t frame, uint32_t min_camera) {
    const Millis timeout(2 * int64_t(o_.timeout_ms));
    for (;;) {
      std::string why;
      std::optional<NumberedCamera> cam = o_.config.camera_mode == CameraMode::lockstep
                                              ? cameras_->take(frame, timeout, &why)
                                              : cameras_->take_latest(min_camera, timeout, &why);
      if (cam) {
        last_camera_ = cam->number;
        return cam;
      }
      if (why == CameraBuffer::kInterrupted) {
        if (cameras_in_->resync_pending()) throw Interrupted{};
        continue;
      }
      if (cameras_in_->client_said_bye()) {  // the render client finished (or gave up: its reason says which)
        std::cerr << who_ << ": " << why << "\n";
        return std::nullopt;
      }
      throw NodeFailure("frame " + std::to_string(frame) + ": " + why);
    }
  }

  // The other node is gone (or misbehaved): drop it and wait for the render client, which
  // notices on its own connection and sends a Resync (Interrupted), or finishes (return).
  void await_instruction(uint32_t frame, const std::string& what) {
    const std::string lost = "frame " + std::to_string(frame) + ": " + other_ + " (" + peer_addr_ + ") " + what;
    drop_peer(who_ + ": " + lost);
    std::cerr << who_ << ": " << lost << "; waiting for the render client\n";
    const Clock::time_point deadline = Clock::now() + Millis(o_.timeout_ms);
    while (Clock::now() < deadline) {
      if (cameras_in_->resync_pending()) throw Interrupted{};
      if (cameras_in_->done()) {
        if (cameras_in_->client_said_bye()) {
          std::cerr << who_ << ": stopped after the " << cameras_in_->end_reason() << "\n";
          return;
        }
        throw NodeFailure(lost + "; then the " + cameras_in_->end_reason());
      }
      poll_for_peer();
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    throw NodeFailure(lost + ", and no word from the render client within " + std::to_string(o_.timeout_ms) + " ms");
  }

  void send_out(const wire::Message& m) {
    if (auto err = rvg_->send(m)) throw NodeFailure("sending to the render client: " + *err);
    if (single_ || !peer_lost_.empty()) return;
    // The render client gets the whole frame even when the other node is gone (it then notices
    // the loss itself); the loss is handled after the frame.
    if (auto err = peer_->send(m)) peer_lost_ = "cannot be sent to: " + *err;
  }

  // OR(frame), depth only: V (V_{frame-2} in the switch, V_{frame-1} alone) for the new camera.
  // A frame without occlusion (the render client's OcclusionGate) draws nothing.
  void draw_occluders(const Camera& cam) {
    drawn_.assign(g_.renderables->count(), 0);
    if (!occlusion_) return;
    g_.renderer->begin_frame(cam, false);
    std::vector<uint32_t> ids(visible_.ids().begin(), visible_.ids().end());
    std::sort(ids.begin(), ids.end());
    for (uint32_t id : ids) drawn_[id] = 1;
    g_.renderer->draw_renderables(*g_.renderables, ids, SceneRenderer::Mode::DepthOnly);
    // Rasterise now, while the other node's stream is awaited: llvmpipe rasterises at a flush
    // (SceneRenderer flushes only every ~20k triangles), so without it the rest of V waited for
    // finish_or() and lengthened the OR's tail, which HC(frame) waits for.
    g_.ctx->gl().Flush();
  }

  // Draws, depth only, those of `ids` that are not in this frame's depth buffer yet (the OR's
  // streamed additions, occluder fusion); all of `ids` count as drawn from now on. Returns the
  // renderables drawn.
  std::vector<uint32_t> draw_new_occluders(std::span<const uint32_t> ids) {
    std::vector<uint32_t> fresh;
    for (uint32_t id : ids)
      if (!drawn_[id]) {
        drawn_[id] = 1;
        fresh.push_back(id);
      }
    if (!fresh.empty()) g_.renderer->draw_renderables(*g_.renderables, fresh, SceneRenderer::Mode::DepthOnly);
    return fresh;
  }

  // The switch from frame `first` (empty sets there): node first % 2 does HC(first).
  void run_switch(uint32_t first) {
    single_ = false;
    const bool latest = o_.config.camera_mode == CameraMode::latest;
    for (uint32_t frame = first + (first % 2 != uint32_t(o_.id));; frame += 2) {
      // ---- OR(frame): camera, clear depth, draw V_{frame-2} then V_{frame-1}'s additions.
      // Latest mode: the newest camera after the one the other node used for frame-1 (the first
      // message of its stream), so no two frames share a camera and the nodes never run ahead of
      // the cameras the render client sent (it sends one per frame received: bounded latency).
      Clock::duration waited{0};  // for the other node's stream: not OR work
      std::optional<wire::Camera> peer_camera;
      uint32_t min_camera = last_camera_ ? *last_camera_ + 1 : 0;
      if (latest && frame > first) {
        // Before or_start: this wait is not inside the OR's time window, so it is not in `waited`
        // (subtracting it from the OR's time made or_us wrap round to ~4e9 in latest mode).
        Clock::duration before_or{0};
        const Clock::time_point deadline = Clock::now() + Millis(o_.timeout_ms);
        std::optional<net::Received> r = next_from_peer(frame - 1, deadline, before_or);
        if (!r) return await_instruction(frame, peer_lost_);
        auto* c = std::get_if<wire::Camera>(&r->message);
        if (!c)
          return await_instruction(frame, "frame " + std::to_string(frame - 1) + ": sent " +
                                              std::string(wire::type_name(wire::type_of(r->message))) +
                                              " before its camera");
        peer_camera = *c;
        min_camera = std::max(min_camera, c->frame + 1);
      }
      std::optional<NumberedCamera> cam = take_camera(frame, min_camera);
      if (!cam) return;
      occlusion_ = cam->occlusion;
      const Clock::time_point or_start = Clock::now();
      const uint64_t or_cpu0 = process_cpu_us();
      tail_cpu0_ = 0;
      tail_t0_ = or_start;
      draw_occluders(cam->camera);
      if (frame > first && !receive_stream(frame - 1, waited, peer_camera)) return await_instruction(frame, peer_lost_);
      finish_or(or_start, or_cpu0, waited);
      // ---- HC(frame): camera to the render client and the other node first (both coarsen
      // their V_{frame-1} with it), then cull and stream the diff.
      try {
        send_out(to_wire(cam->number, cam->camera, {o_.width, o_.height}, uint8_t(cam->occlusion ? 1 : 0)));
      } catch (const std::exception& e) {  // NodeFailure, or a bug/resource error: same clean shutdown
        throw NodeFailure("frame " + std::to_string(frame) + ": sending the camera: " + e.what());
      }
      hc_frame(frame, cam->camera);
      if (!peer_lost_.empty()) return await_instruction(frame, peer_lost_);
    }
  }

  // Alone from frame `first`: OR and HC of every frame on this node, V_{frame-1} as occluders
  // (any subset of the scene's real geometry is a conservative occluder, as in the switch).
  void run_single(uint32_t first) {
    single_ = true;
    for (uint32_t frame = first;; ++frame) {
      poll_for_peer();
      std::optional<NumberedCamera> cam = take_camera(frame, last_camera_ ? *last_camera_ + 1 : 0);
      if (!cam) return;
      occlusion_ = cam->occlusion;
      const Clock::time_point or_start = Clock::now();
      const uint64_t or_cpu0 = process_cpu_us();
      tail_cpu0_ = 0;
      tail_t0_ = or_start;
      draw_occluders(cam->camera);
      finish_or(or_start, or_cpu0, Clock::duration{0});
      send_out(to_wire(cam->number, cam->camera, {o_.width, o_.height}, uint8_t(cam->occlusion ? 1 : 0)));
      hc_frame(frame, cam->camera);
      ++single_frames_;
    }
  }

  void finish_or(Clock::time_point or_start, uint64_t or_cpu0, Clock::duration waited) {
    g_.ctx->gl().Finish();  // the OR's rasterisation belongs to the OR, not to HC's first query
    const uint64_t or_cpu1 = process_cpu_us();
    or_cpu_us_ = uint32_t(or_cpu1 - or_cpu0);
    or_tail_cpu_us_ = uint32_t(or_cpu1 - (tail_cpu0_ ? tail_cpu0_ : or_cpu0));
    or_tail_us_ = micros_since(tail_t0_);
    const uint32_t or_elapsed = micros_since(or_start),
                   or_waited = uint32_t(std::chrono::duration_cast<std::chrono::microseconds>(waited).count());
    or_us_ = or_elapsed > or_waited ? or_elapsed - or_waited : 0;
  }

  // The next message of the other node's stream of `frame`, waiting until `deadline`. nullopt,
  // with peer_lost_ saying why, when the other node is gone or stalls, or the render client
  // finished meanwhile; throws Interrupted when the render client sent a Resync.
  // The other node's Resync on the link marks where its new run of frames starts (follow()):
  // what it sent before the marker this node waits for is stale and skipped. A marker of a newer
  // resync means the other node already follows one this node has not received yet: it reads no
  // further (those messages belong to the new run) until the render client's Resync arrives.
  std::optional<net::Received> next_from_peer(uint32_t frame, Clock::time_point deadline, Clock::duration& waited) {
    const std::string f = "frame " + std::to_string(frame) + ": ";
    for (;;) {
      if (cameras_in_->resync_pending()) throw Interrupted{};
      const Clock::time_point t0 = Clock::now();
      if (peer_resync_seen_) {  // the other node is ahead: wait for ours
        std::this_thread::sleep_for(std::chrono::milliseconds(10));
        waited += Clock::now() - t0;
        if (cameras_in_->done()) {
          peer_lost_ = f + "started over (resync " + std::to_string(peer_resync_seen_) + ") before the render client ended";
          return std::nullopt;
        }
        if (Clock::now() >= deadline) {
          peer_lost_ = f + "started over (resync " + std::to_string(peer_resync_seen_) +
                       "), but the render client's resync did not come within " + std::to_string(o_.timeout_ms) + " ms";
          return std::nullopt;
        }
        continue;
      }
      net::Received r = peer_->receive(Millis(50));
      waited += Clock::now() - t0;
      if (r.ok()) {
        if (const auto* rs = std::get_if<wire::Resync>(&r.message)) {
          if (peer_epoch_wait_ && rs->epoch == peer_epoch_wait_)
            peer_epoch_wait_ = 0;  // what follows is the new run's
          else
            peer_resync_seen_ = rs->epoch;
          continue;
        }
        if (peer_epoch_wait_) continue;  // sent before the other node's marker: stale
        return r;
      }
      if (r.status == net::Received::Status::timeout) {
        if (cameras_in_->done()) peer_lost_ = f + "did not finish its stream before the render client ended";
        else if (Clock::now() >= deadline) peer_lost_ = f + "sent nothing for " + std::to_string(o_.timeout_ms) + " ms";
        else continue;
      } else {
        peer_lost_ = r.status == net::Received::Status::closed ? f + "ended: " + r.reason : f + r.reason;
      }
      return std::nullopt;
    }
  }

  // Applies and draws the other node's diff of `frame` until its EndOfFrame. Returns false, with
  // peer_lost_ saying why, when the other node is gone, stalls or misbehaves, or the render
  // client finished meanwhile; throws Interrupted when the render client sent a Resync.
  // `early`: the stream's camera, already received (latest mode: it chose this node's camera).
  bool receive_stream(uint32_t frame, Clock::duration& waited, const std::optional<wire::Camera>& early) {
    bool cleared = false;  // full-sets mode: the frame's first message replaces the set
    std::vector<uint32_t> before;  // full-sets mode with a hold: V' (sorted)
    bool have_camera = false;
    uint64_t expected_front = 0;
    const std::string f = "frame " + std::to_string(frame) + ": ";
    auto lost = [&](const std::string& why) {
      peer_lost_ = why;
      return false;
    };
    auto start_frame = [&] {
      if (o_.config.full_sets && !cleared) {
        // Full sets resend every id: only those not in V' were found visible (for the hold).
        if (hold_) before.assign(visible_.ids().begin(), visible_.ids().end()), std::sort(before.begin(), before.end());
        visible_.clear();
      }
      cleared = true;
    };
    const Clock::time_point deadline = Clock::now() + Millis(o_.timeout_ms);
    for (bool first = true;; first = false) {
      net::Received r;
      if (first && early) {
        r.status = net::Received::Status::message;
        r.message = *early;
      } else {
        std::optional<net::Received> got = next_from_peer(frame, deadline, waited);
        if (!got) return false;
        r = std::move(*got);
      }
      if (auto* c = std::get_if<wire::Camera>(&r.message)) {
        if (have_camera) return lost(f + "sent two cameras");
        have_camera = true;
        if (auto err = viewport_mismatch(*c, {o_.width, o_.height})) return lost(f + "sent " + *err);
        expected_front = step_->coarsen(visible_, from_wire(*c));
      } else if (auto* d = std::get_if<wire::NodeDiff>(&r.message)) {
        if (!have_camera) return lost(f + "sent its diff before its camera");
        start_frame();
        if (!d->added.empty()) mark_tail();  // the last chunk with additions starts the OR tail
        if (auto err = stream_.on_diff(visible_, *d)) return lost("desync: " + *err);
        if (hold_)  // the other node found these visible in `frame` (added to V')
          for (uint32_t id : d->added)
            if (!o_.config.full_sets || !std::binary_search(before.begin(), before.end(), id))
              hold_->seen(g_.renderables->node_of(id), frame);
        if (occlusion_ && !draw_new_occluders(d->added).empty()) g_.ctx->gl().Flush();  // as in draw_occluders
      } else if (auto* e = std::get_if<wire::EndOfFrame>(&r.message)) {
        if (!have_camera) return lost(f + "sent its diff before its camera");
        start_frame();
        if (!tail_cpu0_) mark_tail();
        if (e->frame != frame) return lost("ended frame " + std::to_string(e->frame) + ", expected " + std::to_string(frame));
        if (auto err = stream_.on_end_of_frame(visible_, *e)) return lost("desync: " + *err);
        if (e->front_hash != expected_front)
          return lost("desync: " + f + "front hash " + hex(e->front_hash) + " from " + other_ + ", " +
                      hex(expected_front) + " here");
        return true;
      } else {
        return lost(f + "sent an unexpected " + std::string(wire::type_name(wire::type_of(r.message))));
      }
    }
  }

  void hc_frame(uint32_t frame, const Camera& cam) {
    const Clock::time_point hc_start = Clock::now();
    hc_cpu0_ = process_cpu_us();
    DiffSender out(uint32_t(o_.diff_chunk_ids), o_.config.full_sets, [this](const wire::Message& m) { send_out(m); });
    if (!occlusion_) {  // the frustum set: every box passes, nothing is learnt from it
      FrustumOnlyQueries all;
      HcFrame hc = step_->hc(frame, visible_, cam, all, {.choices = o_.hc}, out);
      hc.stats.queries = hc.eof.queries = 0;
      end_hc(hc, hc_start, out);
      ++frustum_frames_;
      return;
    }
    HcOptions local{.choices = o_.hc, .skipper = skipper_ ? &*skipper_ : nullptr};
    if (o_.hc.occluder_fusion)
      local.occluders = [&](std::span<const uint32_t> found) {
        // Restores the GL state the queries need; the pyramid is stale where they were drawn.
        const std::vector<uint32_t> drawn = draw_new_occluders(found);
        if (drawn.empty()) return;
        std::vector<Aabb> boxes;
        boxes.reserve(drawn.size());
        for (uint32_t id : drawn) boxes.push_back(g_.renderables->hierarchy().node(g_.renderables->node_of(id)).box);
        querier_->depth_added(boxes);
      };
    querier_->begin(cam);
    HcFrame hc = step_->hc(frame, visible_, cam, *querier_, local, out, hold_ ? &*hold_ : nullptr);
    querier_->end();
    end_hc(hc, hc_start, out);
  }

  // HC's EndOfFrame, with this frame's times, to the render client and the other node.
  void end_hc(HcFrame& hc, Clock::time_point hc_start, DiffSender& out) {
    hc.eof.or_us = or_us_;
    hc.eof.hc_us = micros_since(hc_start);
    hc.eof.hc_cpu_us = uint32_t(process_cpu_us() - hc_cpu0_);
    hc.eof.or_cpu_us = or_cpu_us_;
    hc.eof.or_tail_cpu_us = or_tail_cpu_us_;
    hc.eof.or_tail_us = or_tail_us_;
    out.send(hc.eof);
    ++frames_;
    queries_ += hc.stats.queries;
    assumed_visible_ += hc.stats.skipped;
    pixel_stops_ += hc.stats.pixel_stops;
    hlods_ += hc.stats.hlods;
    skipped_ += hc.tests_above_fronts;
    held_ += hc.held;
  }

  void mark_tail() {
    tail_cpu0_ = process_cpu_us();
    tail_t0_ = Clock::now();
  }

  void print_summary() const {
    if (!rvg_) return;
    auto r = rvg_->stats();
    const uint64_t peer_bytes = peer_sent_bytes_ + (peer_ ? peer_->stats().sent.bytes : 0);
    std::cerr << who_ << ": " << frames_ << " HC frames, " << queries_ << " queries (" << assumed_visible_
              << " more skipped by adaptive queries; " << held_ << " renderables kept by the visibility hold); "
              << frustum_frames_ << " frames without occlusion (the render client's gate), sent " << r.sent.bytes
              << " B to the render client and " << peer_bytes << " B to the other node, peak_rss_mb=" << peak_rss_mb() << "\n";
    if (resyncs_)
      std::cerr << who_ << ": " << resyncs_ << " resyncs from the render client, " << single_frames_
                << " HC frames served alone\n";
    if (querier_) {
      const HcQuerier::Stats& q = querier_->stats();
      std::fprintf(stderr,
                   "%s: HC test %s: %llu boxes tested (%llu occluded): %llu occlusion queries issued, %llu boxes in %llu "
                   "batch draws, %llu proven occluded by the depth pyramid (%.2f M pixels of their rectangles) and %llu shown; of %llu "
                   "tested against it in %llu dispatches; %llu pyramid builds, %llu refreshes after occluder fusion)\n",
                   who_.c_str(), hc_test_name(querier_->mode()), (unsigned long long)q.tests, (unsigned long long)q.occluded,
                   (unsigned long long)q.queries, (unsigned long long)q.batched, (unsigned long long)q.draws,
                   (unsigned long long)q.pyramid_occluded, double(q.pyramid_pixels) / 1e6, (unsigned long long)q.shown,
                   (unsigned long long)q.pyramid_tested, (unsigned long long)q.dispatches, (unsigned long long)q.builds,
                   (unsigned long long)q.refreshes);
    }
    std::fprintf(stderr,
                 "%s: LOD: tau %g px, visible-pixel LOD %s, front tracking %s: %llu HLODs and %llu visible-pixel stops "
                 "chosen; front tracking skipped %llu node tests above the fronts (%.1f per HC frame)\n",
                 who_.c_str(), o_.config.pixel_error, o_.config.visible_pixel_lod ? "on" : "off",
                 o_.config.front_tracking ? "on" : "off", (unsigned long long)hlods_, (unsigned long long)pixel_stops_,
                 (unsigned long long)skipped_, frames_ ? double(skipped_) / double(frames_) : 0.0);
  }

  const NodeOptions& o_;
  std::string who_, other_;
  SceneGl g_;
  wire::Hello mine_;
  std::optional<net::Listener> listener_;  // the whole run; during a session only the Door uses it
  std::unique_ptr<HcQuerier> querier_;
  std::unique_ptr<net::Connection> peer_, rvg_;
  // peer_ (the pointer; the session thread writes it, the Door reads it) and rejoined_peer_ (a
  // restarted node 1 the Door let in, for the session to take).
  std::mutex link_mu_;
  std::unique_ptr<net::Connection> rejoined_peer_;
  std::vector<std::unique_ptr<net::Connection>> dropped_;
  std::string peer_addr_;
  bool peer_fresh_ = false;  // peer_ connected since the last resync
  std::string peer_lost_;    // why the other node is gone (this run of frames)
  uint32_t peer_epoch_wait_ = 0;   // the other node's messages are stale until its marker of this resync
  uint32_t peer_resync_seen_ = 0;  // the other node's marker of a resync this node has not followed yet
  bool single_ = false;      // serving alone (no peer)
  bool occlusion_ = true;    // this frame's camera asks for occlusion (else: the frustum set)
  uint64_t frustum_frames_ = 0;  // HC frames sent as frustum sets (OcclusionGate)
  Clock::time_point next_poll_;
  VisibleSet visible_;
  DiffReceiver stream_;  // diffs of the other node's HC frames
  std::optional<uint32_t> last_camera_;
  uint64_t peer_sent_bytes_ = 0, resyncs_ = 0, single_frames_ = 0;
  uint32_t or_us_ = 0;
  std::optional<CameraBuffer> cameras_;
  std::optional<CameraReceiver> cameras_in_;
  std::optional<SwitchStep> step_;
  std::vector<uint8_t> drawn_;  // renderables in the depth buffer of the current OR/HC frame
  uint64_t tail_cpu0_ = 0, hc_cpu0_ = 0;  // process CPU time (us) at the OR tail's / HC's start
  uint32_t or_cpu_us_ = 0, or_tail_cpu_us_ = 0, or_tail_us_ = 0;
  Clock::time_point tail_t0_;
  uint64_t frames_ = 0, queries_ = 0, skipped_ = 0, pixel_stops_ = 0, hlods_ = 0, assumed_visible_ = 0;
  std::optional<QuerySkipper> skipper_;
  std::optional<VisibilityHold> hold_;
  uint64_t held_ = 0;  // renderables kept in V by the hold (summed over HC frames)
  Door door_;  // last: stopped first (it reads the connections above)
};

}  // namespace

int run_switch_node(const NodeOptions& opts) { return SwitchNode(opts).run(); }

}  // namespace occ
