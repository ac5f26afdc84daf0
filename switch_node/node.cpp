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
#include "common/front.hpp"
#include "common/error.hpp"
#include "common/gl/box_query.hpp"
#include "common/gl/context.hpp"
#include "common/gl/scene_renderer.hpp"
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
    LoadedScene ls = load_and_build(o_.scene, who_, o_.config.lod());
    h_ = &ls.hierarchy;
    if (o_.adaptive_queries == "on") skipper_.emplace(ls.hierarchy.size());
    fingerprint_ = ls.fingerprint;
    renderables_ = std::make_unique<Renderables>(ls.hierarchy, ls.lod.get());
    ctx_ = GlContext::create(parse_gl_backend(o_.gl), o_.width, o_.height);
    std::cerr << who_ << ": GL_RENDERER " << ctx_->renderer() << " (" << ctx_->backend_name() << ")\n";
    renderer_ = std::make_unique<SceneRenderer>(*ctx_, ls.scene, ls.hierarchy, ls.lod.get());
    renderer_->set_occluder_offset(true);  // OR occluders must not hide their own query boxes
    querier_ = std::make_unique<BoxQuerier>(*ctx_);
    connect();
    std::thread camera_thread([this] { receive_cameras(); });
    int code = 0;
    try {
      loop();
    } catch (const std::exception& e) {  // NodeFailure, or a bug/resource error: same clean shutdown
      // A frame in flight when the render client finished (latest mode) is not a failure.
      for (int i = 0; i < 300 && !rvg_->is_open() && !cameras_done_; ++i)
        std::this_thread::sleep_for(std::chrono::milliseconds(10));
      if (!rvg_bye_) {
        std::cerr << "error: " << who_ << ": " << e.what() << "\n";
        code = 1;
        peer_->close_with_error(who_ + " failed: " + e.what());
        rvg_->close_with_error(who_ + " failed: " + e.what());
      } else {
        std::cerr << who_ << ": stopped: " << e.what() << " (after the " << rvg_end_ << ")\n";
      }
    }
    if (code == 0) {
      peer_->close(wire::kByeDone);
    }
    rvg_->close(code ? "failed" : wire::kByeDone);
    camera_thread.join();
    print_summary();
    return code;
  }

 private:
  void connect() {
    Endpoint listen = parse_endpoint("listen", o_.listen);
    auto listener = net::Listener::open(listen.port, listen.host);
    if (!listener) throw std::runtime_error(who_ + ": cannot listen on " + o_.listen + ": " + listener.error());
    if (!o_.port_file.empty())
      if (auto err = net::write_port_file(o_.port_file, listener->port()))
        throw InputError("--port-file '" + o_.port_file + "': " + *err);
    std::cerr << who_ << ": listening on " << listener->address() << ":" << listener->port() << "\n";
    const Millis timeout(o_.timeout_ms);
    const wire::Hello mine = make_hello(wire::Role::switch_node, uint8_t(o_.id), {o_.width, o_.height},
                                        fingerprint_, h_->params(), o_.config, who_);
    if (o_.id == 1) {
      Endpoint pe = parse_endpoint("peer", o_.peer);
      auto conn = net::Connection::connect(pe.host, pe.port, timeout);
      if (!conn) throw std::runtime_error(who_ + ": cannot reach switch node 0 at " + o_.peer + ": " + conn.error());
      auto hello = net::handshake(*conn, mine, {wire::Role::switch_node, uint8_t(0)}, timeout);
      if (!hello) throw std::runtime_error(who_ + ": " + hello.error());
      peer_ = std::make_unique<net::Connection>(std::move(*conn));
      auto rvg = listener->accept_peer(mine, {wire::Role::render_client, std::nullopt}, timeout);
      if (!rvg) throw std::runtime_error(who_ + ": no render client: " + rvg.error());
      rvg_ = std::make_unique<net::Connection>(std::move(rvg->connection));
    } else {
      // Node 0 accepts both the render client and switch node 1, in whatever order they come.
      while (!peer_ || !rvg_) {
        auto p = listener->accept_peer(mine, {}, timeout);
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
    }
    std::cerr << who_ << ": connected: peer " << peer_->peer() << ", render client " << rvg_->peer() << "\n";
  }

  // Camera-receiver thread (paper Fig. 2): every camera from the render client goes into the
  // buffer; its Bye or failure closes the buffer.
  void receive_cameras() {
    for (;;) {
      net::Received r = rvg_->receive(Millis(1000));
      if (r.status == net::Received::Status::timeout) continue;
      if (r.ok()) {
        if (auto* c = std::get_if<wire::Camera>(&r.message)) {
          cameras_.put({c->frame, from_wire(*c)});
          continue;
        }
        rvg_->close_with_error(std::string("unexpected ") + std::string(wire::type_name(wire::type_of(r.message))) +
                               " from the render client");
        cameras_.close("render client sent an unexpected message");
        cameras_done_ = true;
        return;
      }
      rvg_end_ = (r.status == net::Received::Status::closed ? "render client closed: " : "render client failed: ") + r.reason;
      rvg_bye_ = r.status == net::Received::Status::closed;
      cameras_.close(rvg_end_);
      cameras_done_ = true;
      return;
    }
  }

  void send_both(const wire::Message& m) {
    if (auto err = rvg_->send(m)) throw NodeFailure("sending to the render client: " + *err);
    if (auto err = peer_->send(m)) throw NodeFailure("sending to switch node " + std::to_string(1 - o_.id) + ": " + *err);
  }

  std::vector<uint32_t> sorted(const VisibleSet& s) const {
    std::vector<uint32_t> ids(s.ids().begin(), s.ids().end());
    std::sort(ids.begin(), ids.end());
    return ids;
  }

  // Front tracking needs V_{f-1} on every process: not with --full-sets (each frame replaces it).
  bool tracking() const { return o_.config.front_tracking == "on" && !o_.config.full_sets; }

  // Front tracking step 1 (front.hpp) on this process's copy of V_{f-1} for camera f: the set
  // becomes V' (what frame f's diff is relative to); returns set_hash(V'), 0 when not tracking.
  uint64_t coarsen_set(VisibleSet& visible, const Camera& cam) {
    if (!tracking()) return 0;
    LodSelector sel(*renderables_, cam, o_.height, o_.config.pixel_error);
    std::vector<uint32_t> prime = coarsen_visible(sel, visible.ids());
    std::vector<uint32_t> gone;
    for (uint32_t id : visible.ids())
      if (!std::binary_search(prime.begin(), prime.end(), id)) gone.push_back(id);
    for (uint32_t id : gone) visible.erase(id);
    for (uint32_t id : prime) visible.insert(id);
    return front_hash(prime);
  }

  void loop() {
    const Millis timeout(o_.timeout_ms);
    VisibleSet visible(renderables_->count());
    DiffReceiver stream;  // diffs of the other node's HC frames
    std::optional<uint32_t> last_camera;
    for (uint32_t frame = uint32_t(o_.id);; frame += 2) {
      // ---- OR(frame): camera, clear depth, draw V_{frame-2} then V_{frame-1}'s additions.
      std::string why;
      std::optional<NumberedCamera> cam =
          o_.config.camera_mode == "lockstep"
              ? cameras_.take(frame, timeout, &why)
              : cameras_.take_latest(last_camera ? *last_camera + 1 : 0, timeout, &why);
      if (!cam) {
        if (rvg_bye_) {  // the render client finished (or gave up: its reason says which)
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
      renderer_->begin_frame(cam->camera, false);
      std::vector<uint8_t> drawn(renderables_->count(), 0);
      std::vector<uint32_t> ids = sorted(visible);
      for (uint32_t id : ids) drawn[id] = 1;
      renderer_->draw_renderables(*renderables_, ids, SceneRenderer::Mode::DepthOnly);
      Clock::duration waited{0};  // for the other node's stream: not OR work
      if (frame > 0 && !receive_stream(frame - 1, visible, stream, drawn, waited)) return;
      ctx_->gl().Finish();  // the OR's rasterisation belongs to the OR, not to HC's first query
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
  bool receive_stream(uint32_t frame, VisibleSet& visible, DiffReceiver& stream, std::vector<uint8_t>& drawn,
                      Clock::duration& waited) {
    bool cleared = false;  // full-sets mode: the frame's first message replaces the set
    bool have_camera = false;
    uint64_t expected_front = 0;
    auto start_frame = [&] {
      if (!have_camera)
        throw NodeFailure("frame " + std::to_string(frame) + ": switch node " + std::to_string(1 - o_.id) +
                          " sent its diff before its camera");
      if (o_.config.full_sets && !cleared) visible.clear();
      cleared = true;
    };
    for (;;) {
      const Clock::time_point wait_start = Clock::now();
      net::Received r = peer_->receive(Millis(o_.timeout_ms));
      waited += Clock::now() - wait_start;
      if (r.status == net::Received::Status::closed) {
        // The other node finished cleanly (the render client said goodbye to it first): the run
        // is over. Any other goodbye is its failure, and this node fails with it, naming it.
        if (rvg_bye_ || r.reason == std::string("peer said bye: ") + wire::kByeDone) return false;
        throw NodeFailure("frame " + std::to_string(frame) + ": switch node " + std::to_string(1 - o_.id) + " (" +
                          peer_->peer() + ") ended: " + r.reason);
      }
      if (!r.ok())
        throw NodeFailure("frame " + std::to_string(frame) + ": switch node " + std::to_string(1 - o_.id) + " (" +
                          peer_->peer() + ") " + (r.status == net::Received::Status::timeout ? "sent nothing for " + std::to_string(o_.timeout_ms) + " ms" : r.reason));
      if (auto* c = std::get_if<wire::Camera>(&r.message)) {
        if (have_camera)
          throw NodeFailure("frame " + std::to_string(frame) + ": two cameras from switch node " + std::to_string(1 - o_.id));
        have_camera = true;
        expected_front = coarsen_set(visible, from_wire(*c));
      } else if (auto* d = std::get_if<wire::NodeDiff>(&r.message)) {
        start_frame();
        if (!d->added.empty()) mark_tail();  // the last chunk with additions starts the OR tail
        if (auto err = stream.on_diff(visible, *d)) throw NodeFailure("desync: " + *err);
        std::vector<uint32_t> fresh;
        for (uint32_t id : d->added)
          if (!drawn[id]) {
            drawn[id] = 1;
            fresh.push_back(id);
          }
        renderer_->draw_renderables(*renderables_, fresh, SceneRenderer::Mode::DepthOnly);
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
    const uint32_t b = uint32_t(o_.diff_chunk_ids);
    std::vector<uint32_t> pending;
    auto flush = [&](bool force) {
      if (pending.empty() || (!force && pending.size() < b)) return;
      send_both(wire::NodeDiff{frame, pending, {}});
      pending.clear();
    };
    // Front tracking (front.hpp): V' = coarsened V_{frame-1}; fronts derived from it.
    const uint64_t fhash = coarsen_set(visible, cam);
    LodSelector sel(*renderables_, cam, o_.height, o_.config.pixel_error);
    std::vector<uint32_t> start;
    if (tracking()) {
      std::vector<uint32_t> vnodes = nodes_of(*renderables_, sorted(visible)), above;
      start = derive_occluded_front(*h_, vnodes, &above);
      const Frustum fr = cam.frustum();
      if (o_.config.visible_pixel_lod != "on") vnodes = update_cut(*h_, sel, vnodes, &fr);
      start.insert(start.end(), vnodes.begin(), vnodes.end());  // occluded front first
      for (uint32_t a : above)  // what a root traversal would have queried above the fronts
        if (!fr.culls(h_->node(a).box) && !visible_without_query(h_->node(a).box, cam)) ++skipped_;
    }
    querier_->begin(cam);
    CullStats stats;
    SetDiff diff;
    std::vector<uint32_t> leaves = hardware_cull_lod(
        *h_, cam, *querier_, sel, o_.config.visible_pixel_lod == "on", start,
        [&](uint32_t id) {
          if (o_.config.full_sets || !visible.contains(id)) {
            pending.push_back(id);
            diff.added.push_back(id);
            flush(false);
          }
        },
        &stats, skipper_ ? &*skipper_ : nullptr);
    querier_->end();
    flush(true);
    VisibleSet cur(renderables_->count());
    for (uint32_t id : leaves) cur.insert(id);
    if (!o_.config.full_sets) {
      for (uint32_t id : visible.ids())
        if (!cur.contains(id)) diff.removed.push_back(id);
      for (auto& chunk : wire::chunk_node_diff(frame, {}, diff.removed, b)) send_both(chunk);
    }
    wire::EndOfFrame eof = make_end_of_frame(frame, diff, cur);
    eof.front_hash = fhash;
    eof.queries = stats.queries;
    eof.or_us = or_us;
    eof.hc_us = micros_since(hc_start);
    eof.hc_cpu_us = uint32_t(process_cpu_us() - hc_cpu0_);
    eof.or_cpu_us = or_cpu_us_;
    eof.or_tail_cpu_us = or_tail_cpu_us_;
    eof.or_tail_us = or_tail_us_;
    for (uint32_t id : leaves) eof.triangles += renderables_->triangles(id);
    send_both(eof);
    visible = std::move(cur);
    ++frames_;
    queries_ += stats.queries;
    assumed_visible_ += stats.skipped;
    pixel_stops_ += stats.pixel_stops;
    hlods_ += stats.hlods;
  }

  void mark_tail() {
    tail_cpu0_ = process_cpu_us();
    tail_t0_ = Clock::now();
  }

  static std::string hex(uint64_t v) {
    char b[17];
    std::snprintf(b, sizeof b, "%016llx", static_cast<unsigned long long>(v));
    return b;
  }

  void print_summary() const {
    if (!rvg_ || !peer_) return;
    auto r = rvg_->stats(), p = peer_->stats();
    std::cerr << who_ << ": " << frames_ << " HC frames, " << queries_ << " queries (" << assumed_visible_
              << " more skipped by adaptive queries), sent " << r.sent.bytes
              << " B to the render client and " << p.sent.bytes << " B to the other node\n";
    std::fprintf(stderr,
                 "%s: LOD: tau %g px, visible-pixel LOD %s, front tracking %s: %llu HLODs and %llu visible-pixel stops "
                 "chosen; front tracking skipped %llu node tests above the fronts (%.1f per HC frame)\n",
                 who_.c_str(), o_.config.pixel_error, o_.config.visible_pixel_lod.c_str(),
                 o_.config.front_tracking.c_str(), (unsigned long long)hlods_, (unsigned long long)pixel_stops_,
                 (unsigned long long)skipped_, frames_ ? double(skipped_) / double(frames_) : 0.0);
  }

  const NodeOptions& o_;
  std::string who_;
  const Hierarchy* h_ = nullptr;
  uint64_t fingerprint_ = 0;
  std::unique_ptr<Renderables> renderables_;
  std::unique_ptr<GlContext> ctx_;
  std::unique_ptr<SceneRenderer> renderer_;
  std::unique_ptr<BoxQuerier> querier_;
  std::unique_ptr<net::Connection> peer_, rvg_;
  CameraBuffer cameras_;
  std::string rvg_end_;  // why the render client's connection ended (written before cameras_done_)
  std::atomic<bool> rvg_bye_{false}, cameras_done_{false};
  uint64_t tail_cpu0_ = 0, hc_cpu0_ = 0;  // process CPU time (us) at the OR tail's / HC's start
  uint32_t or_cpu_us_ = 0, or_tail_cpu_us_ = 0, or_tail_us_ = 0;
  Clock::time_point tail_t0_;
  uint64_t frames_ = 0, queries_ = 0, skipped_ = 0, pixel_stops_ = 0, hlods_ = 0, assumed_visible_ = 0;
  std::optional<QuerySkipper> skipper_;
};

}  // namespace

int run_switch_node(const NodeOptions& opts) { return SwitchNode(opts).run(); }

}  // namespace occ
