#include "switch_node/node.hpp"

#include <algorithm>
#include <chrono>
#include <optional>
#include <cstdio>
#include <iostream>
#include <thread>

#include "common/camera_buffer.hpp"
#include "common/cpu_time.hpp"
#include "common/culling.hpp"
#include "common/error.hpp"
#include "common/gl/box_query.hpp"
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
    if (o_.hc.adaptive_queries) skipper_.emplace(g_.hierarchy().size());
    if (o_.hc.query_budget) budget_.emplace(g_.hierarchy());
    step_.emplace(*g_.renderables, o_.config, o_.height);
    g_.renderer->set_occluder_offset(true);  // OR occluders must not hide their own query boxes
    querier_ = std::make_unique<BoxQuerier>(*g_.ctx);
    visible_ = VisibleSet(g_.renderables->count());
    connect();
    cameras_in_.emplace(*rvg_, cameras_, Viewport{o_.width, o_.height});
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
    print_summary();
    return code;
  }

 private:
  void connect() {
    listener_.emplace(open_listener(who_, o_.listen));
    const Millis timeout(o_.timeout_ms);
    mine_ = make_hello(wire::Role::switch_node, uint8_t(o_.id), {o_.width, o_.height}, g_.fingerprint(),
                       g_.hierarchy().params(), o_.config, who_);
    if (o_.id == 1) {
      connect_peer(timeout);
      auto rvg = listener_->accept_peer(mine_, {wire::Role::render_client, std::nullopt}, timeout);
      if (!rvg) throw std::runtime_error(who_ + ": no render client: " + rvg.error());
      rvg_ = std::make_unique<net::Connection>(std::move(rvg->connection));
      listener_.reset();  // node 1 connects to its peer; only node 0 takes a new one (rejoin)
    } else {
      // Node 0 accepts both the render client and switch node 1, in whatever order they come.
      while (!peer_ || !rvg_) {
        auto p = listener_->accept_peer(mine_, {}, timeout);
        if (!p) throw std::runtime_error(who_ + ": waiting for peers: " + p.error());
        const bool is_node1 = p->hello.role == wire::Role::switch_node && p->hello.node_id == 1;
        const bool is_rvg = p->hello.role == wire::Role::render_client;
        auto& slot = is_node1 ? peer_ : rvg_;
        if ((!is_node1 && !is_rvg) || slot) {
          p->connection.close_with_error("unexpected peer: " + std::string(wire::role_name(p->hello.role)) + " " +
                                         std::to_string(p->hello.node_id));
          continue;
        }
        slot = std::make_unique<net::Connection>(std::move(p->connection));
      }
      peer_fresh_ = true;
    }
    peer_addr_ = peer_->peer();
    std::cerr << who_ << ": connected: peer " << peer_->peer() << ", render client " << rvg_->peer() << "\n";
  }

  // Node 1: connects to node 0 (--peer) and shakes hands.
  void connect_peer(Millis timeout) {
    const net::Endpoint pe = net::parse_endpoint("peer", o_.peer);
    auto conn = net::Connection::connect(pe.host, pe.port, timeout);
    if (!conn) throw std::runtime_error(who_ + ": cannot reach switch node 0 at " + o_.peer + ": " + conn.error());
    auto hello = net::handshake(*conn, mine_, {wire::Role::switch_node, uint8_t(0)}, timeout);
    if (!hello) throw std::runtime_error(who_ + ": " + hello.error());
    peer_ = std::make_unique<net::Connection>(std::move(*conn));
    peer_fresh_ = true;
    peer_addr_ = peer_->peer();
  }

  // Node 0 without a working peer: takes a switch node 1 that is waiting at the listening port
  // (a restarted node 1 connects to node 0 before it accepts the render client), at most every
  // 100 ms. It serves once the render client's Resync says so.
  void poll_for_peer() {
    if (o_.id != 0 || !listener_ || (peer_ && peer_->is_open())) return;
    const Clock::time_point now = Clock::now();
    if (now < next_poll_) return;
    next_poll_ = now + std::chrono::milliseconds(100);
    auto p = listener_->accept_peer(mine_, {wire::Role::switch_node, uint8_t(1)}, Millis(5));
    if (!p) return;
    drop_peer("replaced");
    peer_ = std::make_unique<net::Connection>(std::move(p->connection));
    peer_fresh_ = true;
    peer_addr_ = peer_->peer();
    std::cerr << who_ << ": " << other_ << " (" << peer_addr_ << ") connected; waiting for the render client's resync\n";
  }

  void drop_peer(const std::string& why) {
    if (!peer_) return;
    const auto st = peer_->stats();
    peer_sent_bytes_ += st.sent.bytes;
    peer_->close_with_error(why);
    dropped_.push_back(std::move(peer_));  // destroyed at the end: closing lingers up to 1.5 s
  }

  // The render client's instruction: start over at r.frame with empty sets, as the switch (2) or
  // alone (1). Answers with the same Resync once ready.
  wire::Resync follow(const wire::Resync& r) {
    ++resyncs_;
    visible_.clear();
    stream_ = DiffReceiver{};
    last_camera_.reset();
    peer_lost_.clear();
    if (r.nodes == 1) {
      drop_peer("the render client dropped " + other_ + " (" + who_ + " serves alone from frame " +
                std::to_string(r.frame) + ")");
    } else if (!peer_ || !peer_->is_open() || !peer_fresh_) {
      drop_peer("resync at frame " + std::to_string(r.frame) + ": a new connection to " + other_);
      const Millis timeout(o_.timeout_ms);
      if (o_.id == 1) {
        connect_peer(timeout);
      } else {
        auto p = listener_->accept_peer(mine_, {wire::Role::switch_node, uint8_t(1)}, timeout);
        if (!p) throw NodeFailure("resync at frame " + std::to_string(r.frame) + ": no " + other_ + ": " + p.error());
        peer_ = std::make_unique<net::Connection>(std::move(p->connection));
        peer_addr_ = peer_->peer();
      }
    }
    peer_fresh_ = false;
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

  // The camera of `frame` (lockstep) or the newest (latest); nullopt when the render client is done.
  // Waits up to twice --timeout-ms: the render client may itself be waiting out its timeout on
  // the other node before it drops that one and sends this one a Resync.
  std::optional<NumberedCamera> take_camera(uint32_t frame) {
    const Millis timeout(2 * int64_t(o_.timeout_ms));
    for (;;) {
      std::string why;
      std::optional<NumberedCamera> cam =
          o_.config.camera_mode == CameraMode::lockstep
              ? cameras_.take(frame, timeout, &why)
              : cameras_.take_latest(last_camera_ ? *last_camera_ + 1 : 0, timeout, &why);
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
  void draw_occluders(const Camera& cam) {
    g_.renderer->begin_frame(cam, false);
    drawn_.assign(g_.renderables->count(), 0);
    std::vector<uint32_t> ids(visible_.ids().begin(), visible_.ids().end());
    std::sort(ids.begin(), ids.end());
    for (uint32_t id : ids) drawn_[id] = 1;
    or_triangles_ = g_.renderer->draw_renderables(*g_.renderables, ids, SceneRenderer::Mode::DepthOnly).triangles;
  }

  // The switch from frame `first` (empty sets there): node first % 2 does HC(first).
  void run_switch(uint32_t first) {
    single_ = false;
    for (uint32_t frame = first + (first % 2 != uint32_t(o_.id));; frame += 2) {
      // ---- OR(frame): camera, clear depth, draw V_{frame-2} then V_{frame-1}'s additions.
      std::optional<NumberedCamera> cam = take_camera(frame);
      if (!cam) return;
      const Clock::time_point or_start = Clock::now();
      const uint64_t or_cpu0 = process_cpu_us();
      tail_cpu0_ = 0;
      tail_t0_ = or_start;
      draw_occluders(cam->camera);
      Clock::duration waited{0};  // for the other node's stream: not OR work
      if (frame > first && !receive_stream(frame - 1, waited)) return await_instruction(frame, peer_lost_);
      finish_or(or_start, or_cpu0, waited);
      // ---- HC(frame): camera to the render client and the other node first (both coarsen
      // their V_{frame-1} with it), then cull and stream the diff.
      try {
        send_out(to_wire(cam->number, cam->camera, {o_.width, o_.height}));
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
      std::optional<NumberedCamera> cam = take_camera(frame);
      if (!cam) return;
      const Clock::time_point or_start = Clock::now();
      const uint64_t or_cpu0 = process_cpu_us();
      tail_cpu0_ = 0;
      tail_t0_ = or_start;
      draw_occluders(cam->camera);
      finish_or(or_start, or_cpu0, Clock::duration{0});
      send_out(to_wire(cam->number, cam->camera, {o_.width, o_.height}));
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
    or_us_ = micros_since(or_start) - uint32_t(std::chrono::duration_cast<std::chrono::microseconds>(waited).count());
  }

  // Applies and draws the other node's diff of `frame` until its EndOfFrame. Returns false, with
  // peer_lost_ saying why, when the other node is gone, stalls or misbehaves, or the render
  // client finished meanwhile; throws Interrupted when the render client sent a Resync.
  bool receive_stream(uint32_t frame, Clock::duration& waited) {
    bool cleared = false;  // full-sets mode: the frame's first message replaces the set
    bool have_camera = false;
    uint64_t expected_front = 0;
    const std::string f = "frame " + std::to_string(frame) + ": ";
    auto lost = [&](const std::string& why) {
      peer_lost_ = why;
      return false;
    };
    const Clock::time_point wait_start = Clock::now();
    const Clock::time_point deadline = wait_start + Millis(o_.timeout_ms);
    for (;;) {
      if (cameras_in_->resync_pending()) {
        waited += Clock::now() - wait_start;
        throw Interrupted{};
      }
      const Clock::time_point t0 = Clock::now();
      net::Received r = peer_->receive(Millis(50));
      waited += Clock::now() - t0;
      if (r.status == net::Received::Status::timeout) {
        if (cameras_in_->done()) return lost("did not finish its stream before the render client ended");
        if (Clock::now() >= deadline) return lost("sent nothing for " + std::to_string(o_.timeout_ms) + " ms");
        continue;
      }
      if (r.status == net::Received::Status::closed) return lost("ended: " + r.reason);
      if (!r.ok()) return lost(r.reason);
      if (auto* c = std::get_if<wire::Camera>(&r.message)) {
        if (have_camera) return lost(f + "sent two cameras");
        have_camera = true;
        if (auto err = viewport_mismatch(*c, {o_.width, o_.height})) return lost(f + "sent " + *err);
        expected_front = step_->coarsen(visible_, from_wire(*c));
      } else if (auto* d = std::get_if<wire::NodeDiff>(&r.message)) {
        if (!have_camera) return lost(f + "sent its diff before its camera");
        if (o_.config.full_sets && !cleared) visible_.clear();
        cleared = true;
        if (!d->added.empty()) mark_tail();  // the last chunk with additions starts the OR tail
        if (auto err = stream_.on_diff(visible_, *d)) return lost("desync: " + *err);
        std::vector<uint32_t> fresh;
        for (uint32_t id : d->added)
          if (!drawn_[id]) {
            drawn_[id] = 1;
            fresh.push_back(id);
          }
        or_triangles_ += g_.renderer->draw_renderables(*g_.renderables, fresh, SceneRenderer::Mode::DepthOnly).triangles;
      } else if (auto* e = std::get_if<wire::EndOfFrame>(&r.message)) {
        if (!have_camera) return lost(f + "sent its diff before its camera");
        if (o_.config.full_sets && !cleared) visible_.clear();
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
    HcLocal local{skipper_ ? &*skipper_ : nullptr, budget_ ? &*budget_ : nullptr, o_.hc.order, nullptr};
    if (o_.hc.occluder_fusion)
      local.occluders = [&](std::span<const uint32_t> found) {
        std::vector<uint32_t> fresh;
        for (uint32_t id : found)
          if (!drawn_[id]) {
            drawn_[id] = 1;
            fresh.push_back(id);
          }
        if (fresh.empty()) return;
        g_.renderer->draw_renderables(*g_.renderables, fresh, SceneRenderer::Mode::DepthOnly);
        querier_->begin(cam);  // the renderer changed the GL state the queries need
      };
    querier_->begin(cam);
    HcFrame hc = step_->hc(frame, visible_, cam, *querier_, local, out);
    querier_->end();
    hc.eof.or_us = or_us_;
    hc.eof.hc_us = micros_since(hc_start);
    hc.eof.hc_cpu_us = uint32_t(process_cpu_us() - hc_cpu0_);
    hc.eof.or_cpu_us = or_cpu_us_;
    hc.eof.or_tail_cpu_us = or_tail_cpu_us_;
    hc.eof.or_tail_us = or_tail_us_;
    out.send(hc.eof);
    if (budget_) update_costs(hc.eof);
    ++frames_;
    queries_ += hc.stats.queries;
    assumed_visible_ += hc.stats.skipped;
    pixel_stops_ += hc.stats.pixel_stops;
    hlods_ += hc.stats.hlods;
    skipped_ += hc.tests_above_fronts;
    whole_ += hc.stats.whole;
  }

  // The query budget's prices, measured on this node (moving averages): a query = HC time per
  // query; a triangle = OR time per triangle drawn, twice (the OR and the render client draw it).
  void update_costs(const wire::EndOfFrame& eof) {
    constexpr double a = 0.2;
    if (eof.queries >= 16) ms_per_query_ = ms_per_query_ == 0 ? eof.hc_us / 1e3 / eof.queries
                                                              : (1 - a) * ms_per_query_ + a * eof.hc_us / 1e3 / eof.queries;
    if (or_triangles_ >= 10000) {
      const double t = 2.0 * eof.or_us / 1e3 / double(or_triangles_);
      ms_per_triangle_ = ms_per_triangle_ == 0 ? t : (1 - a) * ms_per_triangle_ + a * t;
    }
    budget_->set_costs(ms_per_query_, ms_per_triangle_);
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
              << " more skipped by adaptive queries; " << whole_ << " subtrees accepted whole by the query budget, "
              << "a query " << ms_per_query_ << " ms, a triangle " << ms_per_triangle_ * 1e3 << " us), sent " << r.sent.bytes
              << " B to the render client and " << peer_bytes << " B to the other node, peak_rss_mb=" << peak_rss_mb() << "\n";
    if (resyncs_)
      std::cerr << who_ << ": " << resyncs_ << " resyncs from the render client, " << single_frames_
                << " HC frames served alone\n";
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
  std::unique_ptr<BoxQuerier> querier_;
  std::optional<net::Listener> listener_;  // node 0: kept for a restarted node 1
  wire::Hello mine_;
  std::unique_ptr<net::Connection> peer_, rvg_;
  std::vector<std::unique_ptr<net::Connection>> dropped_;
  std::string peer_addr_;
  bool peer_fresh_ = false;  // peer_ connected since the last resync
  std::string peer_lost_;    // why the other node is gone (this run of frames)
  bool single_ = false;      // serving alone (no peer)
  Clock::time_point next_poll_;
  VisibleSet visible_;
  DiffReceiver stream_;  // diffs of the other node's HC frames
  std::optional<uint32_t> last_camera_;
  uint64_t peer_sent_bytes_ = 0, resyncs_ = 0, single_frames_ = 0;
  uint32_t or_us_ = 0;
  CameraBuffer cameras_;
  std::optional<CameraReceiver> cameras_in_;
  std::optional<SwitchStep> step_;
  std::vector<uint8_t> drawn_;  // renderables in the depth buffer of the current OR/HC frame
  std::optional<QueryBudget> budget_;
  uint64_t or_triangles_ = 0;  // drawn by the current OR
  double ms_per_query_ = 0, ms_per_triangle_ = 0;
  uint64_t tail_cpu0_ = 0, hc_cpu0_ = 0;  // process CPU time (us) at the OR tail's / HC's start
  uint32_t or_cpu_us_ = 0, or_tail_cpu_us_ = 0, or_tail_us_ = 0;
  Clock::time_point tail_t0_;
  uint64_t whole_ = 0, frames_ = 0, queries_ = 0, skipped_ = 0, pixel_stops_ = 0, hlods_ = 0, assumed_visible_ = 0;
  std::optional<QuerySkipper> skipper_;
};

}  // namespace

int run_switch_node(const NodeOptions& opts) { return SwitchNode(opts).run(); }

}  // namespace occ
