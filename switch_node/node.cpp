#include "switch_node/node.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <iostream>
#include <optional>
#include <thread>

#include "common/camera_buffer.hpp"
#include "common/cpu_time.hpp"
#include "common/error.hpp"
#include "common/gl/startup.hpp"
#include "common/memory.hpp"
#include "protocol/cluster/camera_receiver.hpp"
#include "protocol/net/transport.hpp"
#include "protocol/visible_set.hpp"
#include "switch_node/cull_frame.hpp"
#include "switch_node/links.hpp"

namespace occ {

namespace {

using Clock = std::chrono::steady_clock;
using net::Millis;

std::string fixed(double v, int digits) {
  char text[64];
  std::snprintf(text, sizeof text, "%.*f", digits, v);
  return text;
}

uint32_t micros_since(Clock::time_point t0) {
  return uint32_t(std::chrono::duration_cast<std::chrono::microseconds>(Clock::now() - t0).count());
}

// The render client sent a Resync (camera_receiver.hpp): the current run of frames stops where it
// is waiting and the loop starts over as the Resync says.
struct Interrupted {};

// What one OR cost, for the EndOfFrame of the HC that follows it (wire.hpp: or_us ...).
struct OrTimes {
  uint32_t us = 0, cpu_us = 0, tail_cpu_us = 0, tail_us = 0;
};

// Counted over one render client, besides the cull frame's CullTotals.
struct SessionStats {
  uint64_t resyncs = 0;        // Resyncs from the render client followed
  uint64_t single_frames = 0;  // HC frames served alone
};

// One render client, from the connections to the summary: the frame schedule (the switch, or
// alone after a resync), with its links and its cull frame. Created fresh for every client, so
// nothing of the last one carries over.
class Session {
 public:
  Session(const NodeOptions& o, SceneGl& g, const BackendChoice& backend, const wire::Hello& mine,
          net::Listener& listener)
      : o_(o),
        who_("switch_node " + std::to_string(o.id)),
        other_("switch node " + std::to_string(1 - o.id)),
        g_(g),
        links_(o, mine, listener),
        cull_(make_backend(backend, *g.ctx, *g.renderer, *g.renderables, g.cpu_occluders.get(), o.config),
              *g.renderables, g.sealed, o.config, with_backend_defaults(o.hc, backend), {o.width, o.height}, other_) {}

  // Returns 0 after the client's Bye.
  int run() {
    links_.connect();
    cameras_in_.emplace(links_.rvg(), cameras_, Viewport{o_.width, o_.height});
    int code = 0;
    try {
      loop();
    } catch (const std::exception& e) {  // NodeFailure, or a bug/resource error: same clean shutdown
      // A frame in flight when the render client finished (latest mode) is not a failure: wait
      // for its goodbye a little before calling it one.
      for (int i = 0; i < 300 && !links_.rvg().is_open() && !cameras_in_->done(); ++i)
        std::this_thread::sleep_for(std::chrono::milliseconds(10));
      if (!cameras_in_->client_said_bye()) {
        std::cerr << "error: " << who_ << ": " << e.what() << "\n";
        code = 1;
        links_.fail(who_ + " failed: " + e.what());
      } else {
        std::cerr << who_ << ": stopped: " << e.what() << " (after the " << cameras_in_->end_reason() << ")\n";
      }
    }
    links_.close(code != 0);
    cameras_in_->join();
    links_.close_door();
    print_summary();
    return code;
  }

 private:
  // The render client's instruction: start over at r.frame with empty sets, as the switch (2) or
  // alone (1). Answers with the same Resync once ready.
  wire::Resync follow(const wire::Resync& r) {
    ++stats_.resyncs;
    cull_.restart();
    last_camera_.reset();
    peer_lost_.clear();
    links_.relink(r);
    // The switch again: the same Resync on the link marks where this node's new run starts (the
    // other node skips what came before it, next_from_peer), and this node skips what the other
    // sent before its own marker (unless that marker was already read).
    peer_epoch_wait_ = 0;
    if (r.nodes == 2) {
      peer_epoch_wait_ = peer_resync_seen_ == r.epoch ? 0 : r.epoch;
      if (auto err = links_.peer()->send(r)) peer_lost_ = "frame " + std::to_string(r.frame) + ": the resync marker: " + *err;
    }
    peer_resync_seen_ = 0;
    std::cerr << who_ << ": resync at frame " << r.frame << " (render client's resync " << r.epoch << "): "
              << (r.nodes == 2 ? "the switch with " + other_ + " (" + links_.peer_addr() + ")" : std::string("serving alone"))
              << ", from empty visible sets\n";
    if (auto err = links_.rvg().send(r)) throw NodeFailure("resync at frame " + std::to_string(r.frame) + ": " + *err);
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
                                              ? cameras_.take(frame, timeout, &why)
                                              : cameras_.take_latest(min_camera, timeout, &why);
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
    const std::string lost = "frame " + std::to_string(frame) + ": " + other_ + " (" + links_.peer_addr() + ") " + what;
    links_.drop_peer(who_ + ": " + lost);
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
      links_.poll_for_peer();
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    throw NodeFailure(lost + ", and no word from the render client within " + std::to_string(o_.timeout_ms) + " ms");
  }

  void send_out(const wire::Message& m) {
    if (auto err = links_.rvg().send(m)) throw NodeFailure("sending to the render client: " + *err);
    if (single_ || !peer_lost_.empty()) return;
    // The render client gets the whole frame even when the other node is gone (it then notices
    // the loss itself); the loss is handled after the frame.
    if (auto err = links_.peer()->send(m)) peer_lost_ = "cannot be sent to: " + *err;
  }

  // OR(frame) starts: V depth only for the new camera (the cull frame), the clocks of its times.
  void start_or(const NumberedCamera& cam) {
    or_start_ = Clock::now();
    or_cpu0_ = process_cpu_us();
    tail_cpu0_ = 0;
    tail_t0_ = or_start_;
    cull_.begin_or(cam.camera, cam.occlusion);
  }

  // The OR's stream part is done: from the last diff chunk with additions on, its time is the tail.
  void mark_tail() {
    tail_cpu0_ = process_cpu_us();
    tail_t0_ = Clock::now();
  }

  // The OR ends (its rasterisation belongs to the OR, not to HC's first query); `waited`: for
  // the other node's stream, not OR work.
  void finish_or(Clock::duration waited) {
    g_.ctx->gl().Finish();
    const uint64_t or_cpu1 = process_cpu_us();
    or_.cpu_us = uint32_t(or_cpu1 - or_cpu0_);
    or_.tail_cpu_us = uint32_t(or_cpu1 - (tail_cpu0_ ? tail_cpu0_ : or_cpu0_));
    or_.tail_us = micros_since(tail_t0_);
    const uint32_t or_elapsed = micros_since(or_start_),
                   or_waited = uint32_t(std::chrono::duration_cast<std::chrono::microseconds>(waited).count());
    or_.us = or_elapsed > or_waited ? or_elapsed - or_waited : 0;
  }

  // The camera HC(frame) uses, to the render client and the other node before the diff (both
  // coarsen their V_{frame-1} with it).
  void send_camera(const NumberedCamera& cam) {
    send_out(to_wire(cam.number, cam.camera, {o_.width, o_.height}, uint8_t(cam.occlusion ? 1 : 0)));
  }

  // HC(frame) after its camera: cull, stream the diff and send the EndOfFrame with this frame's times.
  void hc_frame(uint32_t frame, const NumberedCamera& cam) {
    const Clock::time_point hc_start = Clock::now();
    const uint64_t hc_cpu0 = process_cpu_us();
    DiffSender out(wire::kDefaultDiffChunkIds, [this](const wire::Message& m) { send_out(m); });
    HcFrame hc = cull_.hc(frame, cam.camera, out);
    hc.eof.or_us = or_.us;
    hc.eof.hc_us = micros_since(hc_start);
    hc.eof.hc_cpu_us = uint32_t(process_cpu_us() - hc_cpu0);
    hc.eof.or_cpu_us = or_.cpu_us;
    hc.eof.or_tail_cpu_us = or_.tail_cpu_us;
    hc.eof.or_tail_us = or_.tail_us;
    out.send(hc.eof);
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
        // Before the OR starts: this wait is not inside the OR's time window, so it is not in
        // `waited` (subtracting it from the OR's time made or_us wrap round to ~4e9 in latest mode).
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
      start_or(*cam);
      if (frame > first && !receive_stream(frame - 1, waited, peer_camera)) return await_instruction(frame, peer_lost_);
      finish_or(waited);
      // ---- HC(frame).
      try {
        send_camera(*cam);
      } catch (const std::exception& e) {  // NodeFailure, or a bug/resource error: same clean shutdown
        throw NodeFailure("frame " + std::to_string(frame) + ": sending the camera: " + e.what());
      }
      hc_frame(frame, *cam);
      if (!peer_lost_.empty()) return await_instruction(frame, peer_lost_);
    }
  }

  // Alone from frame `first`: OR and HC of every frame on this node, V_{frame-1} as occluders
  // (any subset of the scene's real geometry is a conservative occluder, as in the switch).
  void run_single(uint32_t first) {
    single_ = true;
    for (uint32_t frame = first;; ++frame) {
      links_.poll_for_peer();
      std::optional<NumberedCamera> cam = take_camera(frame, last_camera_ ? *last_camera_ + 1 : 0);
      if (!cam) return;
      start_or(*cam);
      finish_or(Clock::duration{0});
      send_camera(*cam);
      hc_frame(frame, *cam);
      ++stats_.single_frames;
    }
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
      net::Received r = links_.peer()->receive(Millis(50));
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

  // The other node's stream of `frame`, into the cull frame, until its EndOfFrame. Returns false,
  // with peer_lost_ saying why, when the other node is gone, stalls or misbehaves, or the render
  // client finished meanwhile; throws Interrupted when the render client sent a Resync.
  // `early`: the stream's camera, already received (latest mode: it chose this node's camera).
  bool receive_stream(uint32_t frame, Clock::duration& waited, const std::optional<wire::Camera>& early) {
    const Clock::time_point deadline = Clock::now() + Millis(o_.timeout_ms);
    cull_.begin_stream(frame);
    for (bool first = true;; first = false) {
      wire::Message m;
      if (first && early) {
        m = *early;
      } else {
        std::optional<net::Received> got = next_from_peer(frame, deadline, waited);
        if (!got) return false;
        m = std::move(got->message);
      }
      // The last chunk with additions starts the OR's tail (or the EndOfFrame, if none has).
      if (const auto* d = std::get_if<wire::NodeDiff>(&m); d && !d->added.empty()) mark_tail();
      if (std::holds_alternative<wire::EndOfFrame>(m) && !tail_cpu0_) mark_tail();
      Result<CullFrame::Stream> step = cull_.take(m);
      if (!step) {
        peer_lost_ = step.error();
        return false;
      }
      if (*step == CullFrame::Stream::done) return true;
    }
  }

  void print_summary() const {
    const CullTotals& t = cull_.totals();
    std::cerr << who_ << ": " << t.frames << " HC frames, " << t.assumed_visible
              << " nodes assumed visible by adaptive queries (" << t.skipped_occluded
              << " others they skipped proven occluded by the depth pyramid; " << t.held
              << " renderables kept by the visibility hold); "
              << t.frustum_frames << " frames without occlusion (the render client's gate; " << t.ors_after_frustum_sets
              << " ORs after them drew no frustum set), sent "
              << links_.rvg().stats().sent.bytes << " B to the render client and " << links_.peer_sent_bytes()
              << " B to the other node, peak_rss_mb=" << peak_rss_mb() << "\n";
    const net::ConnectionStats r = links_.rvg().stats();  // on the wire: with TLS's records (docs/security.md)
    std::cerr << who_ << ": link to the render client (" << (links_.rvg().encrypted() ? "TLS 1.3" : "plain TCP")
              << "): " << r.sent.bytes << " B of messages sent as " << r.socket_bytes_sent << " B on the wire, "
              << r.received.bytes << " B received as " << r.socket_bytes_received << " B\n";
    if (stats_.resyncs)
      std::cerr << who_ << ": " << stats_.resyncs << " resyncs from the render client, " << stats_.single_frames
                << " HC frames served alone\n";
    // What the back end did, from its own counts (tests and scripts read this line).
    const OcclusionCounts c = cull_.backend().counts();
    std::cerr << who_ << ": occlusion back end " << cull_.backend().name() << ": " << c.boxes_tested
              << " boxes tested (" << c.boxes_occluded << " occluded)";
    for (const std::string& more : c.more) std::cerr << ", " << more;
    std::cerr << "\n";
    std::cerr.flush();
    print_geometry_line(stderr, who_, g_.renderer->geometry_pool());
    std::cerr << who_ << ": LOD: tau " << o_.config.pixel_error << " px, visible-pixel LOD "
              << (o_.config.visible_pixel_lod ? "on" : "off") << ", front tracking "
              << (o_.config.front_tracking ? "on" : "off") << ": " << t.hlods << " HLODs and " << t.pixel_stops
              << " visible-pixel stops chosen; front tracking skipped " << t.tests_above_fronts
              << " node tests above the fronts ("
              << fixed(t.frames ? double(t.tests_above_fronts) / double(t.frames) : 0.0, 1) << " per HC frame)\n";
  }

  const NodeOptions& o_;
  const std::string who_, other_;
  SceneGl& g_;
  Links links_;
  CameraBuffer cameras_;
  std::optional<CameraReceiver> cameras_in_;  // after links_ and cameras_: stopped first
  CullFrame cull_;
  // The schedule's state.
  bool single_ = false;              // serving alone (no peer)
  std::optional<uint32_t> last_camera_;
  std::string peer_lost_;            // why the other node is gone (this run of frames)
  uint32_t peer_epoch_wait_ = 0;     // the other node's messages are stale until its marker of this resync
  uint32_t peer_resync_seen_ = 0;    // the other node's marker of a resync this node has not followed yet
  // The OR's clocks (start_or, mark_tail) and its times (finish_or).
  Clock::time_point or_start_, tail_t0_;
  uint64_t or_cpu0_ = 0, tail_cpu0_ = 0;  // process CPU time (us) at the OR's / its tail's start
  OrTimes or_;
  SessionStats stats_;
};

class SwitchNode {
 public:
  explicit SwitchNode(const NodeOptions& o) : o_(o), who_("switch_node " + std::to_string(o.id)) {}

  int run() {
    // Found, or copied, while the geometry is still on the CPU (the upload releases it).
    Enclosures sealed;
    std::optional<CpuOccluders> cpu;
    g_ = start_scene_gl(who_, o_.scene, o_.config.lod(), o_.gl, o_.width, o_.height, nullptr,
                        [&](const LoadedScene& ls, const GlContext& ctx) {
                          if (o_.hc.sealed) sealed = find_enclosures(who_, ls.scene, ls.hierarchy);
                          const bool in_memory = !ls.scene.mapped && !ls.scene.geometry_released();
                          backend_ = choose_backend_for(ctx, o_.config, o_.hc, in_memory);
                          if (backend_.kind == BackendKind::cpu) {
                            std::string why;
                            cpu = CpuOccluders::copy(ls.scene, ls.hierarchy, o_.width, o_.height, &why);
                            if (!cpu) throw InputError("--backend cpu: " + why);
                          }
                        });
    g_.sealed = std::move(sealed);
    if (cpu) g_.cpu_occluders = std::make_unique<CpuOccluders>(std::move(*cpu));
    std::cerr << who_ << ": " << backend_line(backend_);
    if (g_.cpu_occluders)
      std::cerr << " (" << fixed(double(g_.cpu_occluders->bytes()) / 1048576.0, 1) << " MB of triangles on the CPU)";
    std::cerr << "\n";
    mine_ = make_hello(wire::Role::switch_node, uint8_t(o_.id), {o_.width, o_.height}, g_.fingerprint(),
                       g_.hierarchy().params(), o_.config, who_, backend_name(backend_.kind));
    // Both nodes keep their listener for the whole run: node 0 takes a restarted node 1 through it
    // (the door hands it over), and it tells a second render client the cluster is busy.
    listener_.emplace(open_listener(who_, o_.listen));
    if (!o_.serve) return serve_one();
    // --serve: one render client after the other, each in a session of its own (both nodes
    // start it from scratch: new connections, including the link between the nodes, and fresh
    // per-client state), until --serve's number of clients have been served (or forever).
    int failed = 0;
    for (int n = 1;; ++n) {
      const int code = serve_one();
      failed += code != 0;
      if (o_.sessions > 0 && n >= o_.sessions) {
        std::cerr << who_ << ": served " << n << " render clients (" << failed << " failed), as --serve asked\n";
        return failed ? 1 : 0;
      }
      std::cerr << who_ << ": render client " << n << (code ? " failed" : " done")
                << "; waiting for the next one (--serve)\n";
    }
  }

 private:
  int serve_one() { return Session(o_, g_, backend_, mine_, *listener_).run(); }

  const NodeOptions& o_;
  std::string who_;
  SceneGl g_;
  BackendChoice backend_;  // chosen once at start
  wire::Hello mine_;
  std::optional<net::Listener> listener_;
};

}  // namespace

int run_switch_node(const NodeOptions& opts) { return SwitchNode(opts).run(); }

}  // namespace occ
