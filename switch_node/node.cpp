#include "switch_node/node.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
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

class SwitchNode {
 public:
  explicit SwitchNode(const NodeOptions& o) : o_(o), who_("switch_node " + std::to_string(o.id)) {}

  int run() {
    g_ = start_scene_gl(who_, o_.scene, o_.config.lod(), o_.gl, o_.width, o_.height);
    g_.renderer->set_occluder_offset(true);  // OR occluders must not hide their own query boxes
    mine_ = make_hello(wire::Role::switch_node, uint8_t(o_.id), {o_.width, o_.height}, g_.fingerprint(),
                       g_.hierarchy().params(), o_.config, who_);
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
      // A frame in flight when the render client finished (latest mode) is not a failure; nor is
      // the other node's clean goodbye racing the render client's own goodbye to this node (the
      // client says goodbye to node 0 first): wait for it a little before calling it a failure.
      const bool peer_done = peer_ended_cleanly_;
      for (int i = 0; i < 300 && (peer_done || !rvg_->is_open()) && !cameras_in_->done(); ++i)
        std::this_thread::sleep_for(std::chrono::milliseconds(10));
      if (!cameras_in_->client_said_bye()) {
        std::cerr << "error: " << who_ << ": " << e.what() << "\n";
        code = 1;
        peer_->close_with_error(who_ + " failed: " + e.what());
        rvg_->close_with_error(who_ + " failed: " + e.what());
      } else {
        std::cerr << who_ << ": stopped: " << e.what() << " (after the " << cameras_in_->end_reason() << ")\n";
      }
    }
    if (code == 0) {
      peer_->close(wire::kByeDone);
    }
    rvg_->close(code ? "failed" : wire::kByeDone);
    cameras_in_->join();
    door_.stop();
    print_summary();
    return code;
  }

  // Everything that belongs to one render client starts afresh: connections, cameras, the query
  // history of adaptive queries, the measured query budget, statistics. (The visible set, the
  // fronts and the diff streams live in loop().)
  void reset_client_state() {
    cameras_in_.reset();
    peer_.reset();
    rvg_.reset();
    cameras_.emplace();
    skipper_.reset();
    budget_.reset();
    hold_.reset();
    if (o_.hc.adaptive_queries) skipper_.emplace(g_.hierarchy().size());
    if (o_.hc.query_budget) budget_.emplace(g_.hierarchy());
    if (o_.hc.visibility_hold > 0) hold_.emplace(g_.hierarchy().size(), uint32_t(o_.hc.visibility_hold));
    step_.emplace(*g_.renderables, o_.config, o_.height);
    querier_.reset();
    // Sample counts only matter to visible-pixel LOD (a node with fewer than tau samples stops).
    querier_ = std::make_unique<HcQuerier>(*g_.ctx, o_.hc.test, o_.config.visible_pixel_lod && o_.config.lod());
    peer_ended_cleanly_ = false;
    or_triangles_ = 0;
    ms_per_query_ = ms_per_triangle_ = 0;
    tail_cpu0_ = hc_cpu0_ = 0;
    or_cpu_us_ = or_tail_cpu_us_ = or_tail_us_ = 0;
    whole_ = frames_ = queries_ = skipped_ = pixel_stops_ = hlods_ = assumed_visible_ = 0;
  }

  net::PeerExpectation expect(std::optional<wire::Role> role, std::optional<uint8_t> node_id) const {
    net::PeerExpectation e{role, node_id};
    e.key = o_.key ? &*o_.key : nullptr;
    return e;
  }

  // Why this node turns away a connector whose slot is taken (nullopt: it may have the slot).
  std::optional<std::string> busy_reason(const wire::Hello& h) const {
    const bool is_node1 = o_.id == 0 && h.role == wire::Role::switch_node && h.node_id == 1;
    const bool is_rvg = h.role == wire::Role::render_client;
    if (!is_node1 && !is_rvg)
      return "unexpected peer: " + std::string(wire::role_name(h.role)) + " " + std::to_string(h.node_id);
    const auto& slot = is_node1 ? peer_ : rvg_;
    if (!slot || !slot->is_open()) return std::nullopt;
    return std::string(wire::kByeBusy) + who_ + " is serving " +
           (is_rvg ? "another render client (" + rvg_->peer() + ")" : "switch node 1 (" + peer_->peer() + ")") +
           "; try again when it has finished";
  }

  // Waits for a peer on the listener: for --timeout-ms, or (--serve) as long as it takes.
  net::Peer accept(const net::PeerExpectation& e, const std::string& what) {
    for (;;) {
      auto p = listener_->accept_peer(mine_, e, Millis(o_.timeout_ms));
      if (p) return std::move(*p);
      if (!o_.serve) throw std::runtime_error(who_ + ": " + what + ": " + p.error());
      if (p.error().find("no valid peer") == std::string::npos) {  // not a timeout: do not spin
        std::cerr << who_ << ": " << what << ": " << p.error() << "\n";
        std::this_thread::sleep_for(std::chrono::milliseconds(100));
      }
    }
  }

  // Node 1: the link to node 0. Node 0 may still be finishing its last client (--serve): it says
  // "busy" until then, and this retries.
  void connect_peer() {
    const Millis timeout(o_.timeout_ms);
    const net::Endpoint pe = net::parse_endpoint("peer", o_.peer);
    const auto deadline = Clock::now() + timeout;
    for (;;) {
      auto conn = net::Connection::connect(pe.host, pe.port, timeout);
      if (!conn) throw std::runtime_error(who_ + ": cannot reach switch node 0 at " + o_.peer + ": " + conn.error());
      auto hello = net::handshake(*conn, mine_, expect(wire::Role::switch_node, uint8_t(0)), timeout);
      if (hello) {
        peer_ = std::make_unique<net::Connection>(std::move(*conn));
        return;
      }
      if (hello.error().find(wire::kByeBusy) == std::string::npos || Clock::now() > deadline)
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
        const bool is_node1 = p.hello.role == wire::Role::switch_node;
        (is_node1 ? peer_ : rvg_) = std::make_unique<net::Connection>(std::move(p.connection));
      }
    }
    std::cerr << who_ << ": connected: peer " << peer_->peer() << ", render client " << rvg_->peer() << "\n";
  }

  // While a client is served, the listener stays open and every connector gets Bye("busy: ...")
  // in its handshake (after its hello and key were checked): a second render client learns at
  // once that the cluster is busy, node 1 coming back early for the next client retries.
  class Door {
   public:
    ~Door() { stop(); }
    void start(SwitchNode& node) {
      stop();
      stop_ = false;
      thread_ = std::thread([this, &node] {
        net::PeerExpectation e = node.expect(std::nullopt, std::nullopt);
        e.refuse = [&node](const wire::Hello& h) {
          auto why = node.busy_reason(h);
          return why ? why : std::optional<std::string>(std::string(wire::kByeBusy) + node.who_ + " is serving a render client; try again when it has finished");
        };
        while (!stop_) {
          auto conn = node.listener_->accept(Millis(100));
          if (!conn) continue;
          (void)net::handshake(*conn, node.mine_, e, Millis(2000));  // refused (and logged) in every case
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

  void send_both(const wire::Message& m) {
    if (auto err = rvg_->send(m)) throw NodeFailure("sending to the render client: " + *err);
    if (auto err = peer_->send(m)) {
      peer_ended_cleanly_ = err->find(std::string("peer said bye: ") + wire::kByeDone) != std::string::npos;
      throw NodeFailure("sending to switch node " + std::to_string(1 - o_.id) + ": " + *err);
    }
  }

  void loop() {
    const Millis timeout(o_.timeout_ms);
    VisibleSet visible(g_.renderables->count());
    DiffReceiver stream;  // diffs of the other node's HC frames
    std::optional<uint32_t> last_camera;
    for (uint32_t frame = uint32_t(o_.id);; frame += 2) {
      // ---- OR(frame): camera, clear depth, draw V_{frame-2} then V_{frame-1}'s additions.
      // Latest mode: the newest camera after the one the other node used for frame-1 (the first
      // message of its stream), so no two frames share a camera and the nodes never run ahead of
      // the cameras the render client sent (it sends one per frame received: bounded latency).
      std::string why;
      Clock::duration waited{0};  // for the other node's stream: not OR work
      std::optional<wire::Camera> peer_camera;
      uint32_t min_camera = last_camera ? *last_camera + 1 : 0;
      if (o_.config.camera_mode == CameraMode::latest && frame > 0) {
        const Clock::time_point wait_start = Clock::now();
        std::optional<net::Received> r = receive_peer(frame - 1);
        waited += Clock::now() - wait_start;
        if (!r) return;  // the other node finished cleanly
        auto* c = std::get_if<wire::Camera>(&r->message);
        if (!c)
          throw NodeFailure("frame " + std::to_string(frame - 1) + ": switch node " + std::to_string(1 - o_.id) +
                            " sent " + std::string(wire::type_name(wire::type_of(r->message))) + " before its camera");
        peer_camera = *c;
        min_camera = std::max(min_camera, c->frame + 1);
      }
      std::optional<NumberedCamera> cam =
          o_.config.camera_mode == CameraMode::lockstep
              ? cameras_->take(frame, timeout, &why)
              : cameras_->take_latest(min_camera, timeout, &why);
      if (!cam) {
        if (cameras_in_->client_said_bye()) {  // the render client finished (or gave up: its reason says which)
          std::cerr << who_ << ": " << why << "\n";
          return;
        }
        throw NodeFailure("frame " + std::to_string(frame) + ": " + why);
      }
      last_camera = cam->number;
      const Clock::time_point or_start = Clock::now();
      const uint64_t or_cpu0 = process_cpu_us();
      tail_cpu0_ = 0;
      tail_t0_ = or_start;
      g_.renderer->begin_frame(cam->camera, false);
      std::vector<uint8_t>& drawn = drawn_;  // what this frame's depth buffer holds
      drawn.assign(g_.renderables->count(), 0);
      std::vector<uint32_t> ids(visible.ids().begin(), visible.ids().end());
      std::sort(ids.begin(), ids.end());
      for (uint32_t id : ids) drawn[id] = 1;
      or_camera_ = cam->camera;
      select_.filter(ids, *g_.renderables, or_camera_, o_.height);
      or_triangles_ = g_.renderer->draw_renderables(*g_.renderables, ids, SceneRenderer::Mode::DepthOnly).triangles;
      if (frame > 0 && !receive_stream(frame - 1, visible, stream, drawn, waited, peer_camera)) return;
      g_.ctx->gl().Finish();  // the OR's rasterisation belongs to the OR, not to HC's first query
      const uint64_t or_cpu1 = process_cpu_us();
      or_cpu_us_ = uint32_t(or_cpu1 - or_cpu0);
      or_tail_cpu_us_ = uint32_t(or_cpu1 - (tail_cpu0_ ? tail_cpu0_ : or_cpu0));
      or_tail_us_ = micros_since(tail_t0_);
      const uint32_t or_us =
          micros_since(or_start) - uint32_t(std::chrono::duration_cast<std::chrono::microseconds>(waited).count());

      // ---- HC(frame): camera to the render client and the other node first (both coarsen
      // their V_{frame-1} with it), then cull and stream the diff.
      try {
        send_both(to_wire(cam->number, cam->camera, {o_.width, o_.height}));
      } catch (const std::exception& e) {  // NodeFailure, or a bug/resource error: same clean shutdown
        throw NodeFailure("frame " + std::to_string(frame) + ": sending the camera: " + e.what());
      }
      const Clock::time_point hc_start = Clock::now();
      hc_cpu0_ = process_cpu_us();
      hc_frame(frame, cam->camera, visible, or_us, hc_start);
    }
  }

  // Applies and draws the other node's diff of `frame` until its EndOfFrame. Returns false when
  // the other node closed cleanly instead (the run is over).
  // The next message of the other node's stream of `frame`; nullopt when it closed cleanly
  // (the render client said goodbye to it first: the run is over). Any other goodbye is its
  // failure, and this node fails with it, naming it.
  std::optional<net::Received> receive_peer(uint32_t frame) {
    net::Received r = peer_->receive(Millis(o_.timeout_ms));
    if (r.status == net::Received::Status::closed) {
      if (cameras_in_->client_said_bye() || r.reason == std::string("peer said bye: ") + wire::kByeDone) return std::nullopt;
      throw NodeFailure("frame " + std::to_string(frame) + ": switch node " + std::to_string(1 - o_.id) + " (" +
                        peer_->peer() + ") ended: " + r.reason);
    }
    if (!r.ok())
      throw NodeFailure("frame " + std::to_string(frame) + ": switch node " + std::to_string(1 - o_.id) + " (" +
                        peer_->peer() + ") " + (r.status == net::Received::Status::timeout ? "sent nothing for " + std::to_string(o_.timeout_ms) + " ms" : r.reason));
    return r;
  }

  // `early`: the stream's camera, already received (latest mode: it chose this node's camera).
  bool receive_stream(uint32_t frame, VisibleSet& visible, DiffReceiver& stream, std::vector<uint8_t>& drawn,
                      Clock::duration& waited, const std::optional<wire::Camera>& early) {
    bool cleared = false;  // full-sets mode: the frame's first message replaces the set
    std::vector<uint32_t> before;  // full-sets mode with a hold: V' (sorted)
    bool have_camera = false;
    uint64_t expected_front = 0;
    auto start_frame = [&] {
      if (!have_camera)
        throw NodeFailure("frame " + std::to_string(frame) + ": switch node " + std::to_string(1 - o_.id) +
                          " sent its diff before its camera");
      if (o_.config.full_sets && !cleared) {
        // Full sets resend every id: only those not in V' were found visible (for the hold).
        if (hold_) before.assign(visible.ids().begin(), visible.ids().end()), std::sort(before.begin(), before.end());
        visible.clear();
      }
      cleared = true;
    };
    for (bool first = true;; first = false) {
      net::Received r;
      if (first && early) {
        r.status = net::Received::Status::message;
        r.message = *early;
      } else {
        const Clock::time_point wait_start = Clock::now();
        std::optional<net::Received> got = receive_peer(frame);
        waited += Clock::now() - wait_start;
        if (!got) return false;
        r = std::move(*got);
      }
      if (auto* c = std::get_if<wire::Camera>(&r.message)) {
        if (have_camera)
          throw NodeFailure("frame " + std::to_string(frame) + ": two cameras from switch node " + std::to_string(1 - o_.id));
        have_camera = true;
        if (auto err = viewport_mismatch(*c, {o_.width, o_.height}))
          throw NodeFailure("frame " + std::to_string(frame) + ": switch node " + std::to_string(1 - o_.id) + " sent " + *err);
        expected_front = step_->coarsen(visible, from_wire(*c));
      } else if (auto* d = std::get_if<wire::NodeDiff>(&r.message)) {
        start_frame();
        if (!d->added.empty()) mark_tail();  // the last chunk with additions starts the OR tail
        if (auto err = stream.on_diff(visible, *d)) throw NodeFailure("desync: " + *err);
        if (hold_)  // the other node found these visible in `frame` (added to V')
          for (uint32_t id : d->added)
            if (!o_.config.full_sets || !std::binary_search(before.begin(), before.end(), id))
              hold_->seen(g_.renderables->node_of(id), frame);
        std::vector<uint32_t> fresh;
        for (uint32_t id : d->added)
          if (!drawn[id]) {
            drawn[id] = 1;
            fresh.push_back(id);
          }
        select_.filter(fresh, *g_.renderables, or_camera_, o_.height);
        or_triangles_ += g_.renderer->draw_renderables(*g_.renderables, fresh, SceneRenderer::Mode::DepthOnly).triangles;
      } else if (auto* e = std::get_if<wire::EndOfFrame>(&r.message)) {
        start_frame();
        if (!tail_cpu0_) mark_tail();
        if (e->frame != frame) throw NodeFailure("expected the end of frame " + std::to_string(frame) + ", got " + std::to_string(e->frame));
        if (auto err = stream.on_end_of_frame(visible, *e)) throw NodeFailure("desync: " + *err);
        if (e->front_hash != expected_front)
          throw NodeFailure("desync: frame " + std::to_string(frame) + ": front hash " + hex(e->front_hash) +
                            " from switch node " + std::to_string(1 - o_.id) + ", " + hex(expected_front) + " here");
        return true;
      } else {
        throw NodeFailure("frame " + std::to_string(frame) + ": unexpected " +
                          std::string(wire::type_name(wire::type_of(r.message))) + " from the other switch node");
      }
    }
  }

  void hc_frame(uint32_t frame, const Camera& cam, VisibleSet& visible, uint32_t or_us, Clock::time_point hc_start) {
    DiffSender out(uint32_t(o_.diff_chunk_ids), o_.config.full_sets, [this](const wire::Message& m) { send_both(m); });
    HcLocal local{skipper_ ? &*skipper_ : nullptr, budget_ ? &*budget_ : nullptr, o_.hc.order, nullptr,
                  hold_ ? &*hold_ : nullptr};
    if (o_.hc.occluder_fusion)
      local.occluders = [&](std::span<const uint32_t> found) {
        std::vector<uint32_t> fresh;
        for (uint32_t id : found)
          if (!drawn_[id]) {
            drawn_[id] = 1;
            fresh.push_back(id);
          }
        select_.filter(fresh, *g_.renderables, cam, o_.height);
        if (fresh.empty()) return;
        g_.renderer->draw_renderables(*g_.renderables, fresh, SceneRenderer::Mode::DepthOnly);
        querier_->depth_added();  // restores the GL state the queries need; the pyramid is stale
      };
    querier_->begin(cam);
    HcFrame hc = step_->hc(frame, visible, cam, *querier_, local, out);
    querier_->end();
    hc.eof.or_us = or_us;
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
    held_ += hc.held;
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
    if (!rvg_ || !peer_) return;
    auto r = rvg_->stats(), p = peer_->stats();
    std::cerr << who_ << ": " << frames_ << " HC frames, " << queries_ << " queries (" << assumed_visible_
              << " more skipped by adaptive queries; " << whole_ << " subtrees accepted whole by the query budget, "
              << "a query " << ms_per_query_ << " ms, a triangle " << ms_per_triangle_ * 1e3 << " us; " << held_
              << " renderables kept by the visibility hold), sent " << r.sent.bytes
              << " B to the render client and " << p.sent.bytes << " B to the other node, peak_rss_mb=" << peak_rss_mb() << "\n";
    if (querier_) {
      const HcQuerier::Stats& q = querier_->stats();
      static constexpr const char* kTest[] = {"queries", "pyramid", "auto", "batch"};
      std::fprintf(stderr,
                   "%s: HC test %s: %llu boxes tested (%llu occluded): %llu occlusion queries issued, %llu boxes in %llu "
                   "batch draws, %llu proven occluded by the depth pyramid (of %llu tested against it in %llu "
                   "dispatches; %llu pyramid builds)\n",
                   who_.c_str(), kTest[int(querier_->mode())], (unsigned long long)q.tests, (unsigned long long)q.occluded,
                   (unsigned long long)q.queries, (unsigned long long)q.batched, (unsigned long long)q.draws,
                   (unsigned long long)q.pyramid_occluded,
                   (unsigned long long)q.pyramid_tested, (unsigned long long)q.dispatches, (unsigned long long)q.builds);
    }
    std::fprintf(stderr,
                 "%s: LOD: tau %g px, visible-pixel LOD %s, front tracking %s: %llu HLODs and %llu visible-pixel stops "
                 "chosen; front tracking skipped %llu node tests above the fronts (%.1f per HC frame)\n",
                 who_.c_str(), o_.config.pixel_error, o_.config.visible_pixel_lod ? "on" : "off",
                 o_.config.front_tracking ? "on" : "off", (unsigned long long)hlods_, (unsigned long long)pixel_stops_,
                 (unsigned long long)skipped_, frames_ ? double(skipped_) / double(frames_) : 0.0);
  }

  const NodeOptions& o_;
  std::string who_;
  SceneGl g_;
  wire::Hello mine_;
  std::optional<net::Listener> listener_;
  std::unique_ptr<HcQuerier> querier_;
  std::unique_ptr<net::Connection> peer_, rvg_;
  std::optional<CameraBuffer> cameras_;
  std::optional<CameraReceiver> cameras_in_;
  std::optional<SwitchStep> step_;
  std::vector<uint8_t> drawn_;  // renderables in the depth buffer of the current OR/HC frame
  OccluderSelection select_{o_.hc.occluder_pixels_per_triangle};
  Camera or_camera_;            // the current OR's camera (occluder selection of streamed additions)
  std::optional<QueryBudget> budget_;
  bool peer_ended_cleanly_ = false;  // a send to the other node failed after its clean goodbye
  uint64_t or_triangles_ = 0;  // drawn by the current OR
  double ms_per_query_ = 0, ms_per_triangle_ = 0;
  uint64_t tail_cpu0_ = 0, hc_cpu0_ = 0;  // process CPU time (us) at the OR tail's / HC's start
  uint32_t or_cpu_us_ = 0, or_tail_cpu_us_ = 0, or_tail_us_ = 0;
  Clock::time_point tail_t0_;
  uint64_t whole_ = 0, frames_ = 0, queries_ = 0, skipped_ = 0, pixel_stops_ = 0, hlods_ = 0, assumed_visible_ = 0;
  std::optional<QuerySkipper> skipper_;
  std::optional<VisibilityHold> hold_;
  uint64_t held_ = 0;  // renderables kept in V by the hold (summed over HC frames)
  Door door_;  // last: stopped first (it reads the connections above)
};

}  // namespace

int run_switch_node(const NodeOptions& opts) { return SwitchNode(opts).run(); }

}  // namespace occ
