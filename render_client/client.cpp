// The RVG display client (paper 4.5): sends cameras to both switch nodes, receives the camera
// actually used for frame f, the diff and EndOfFrame from the node doing HC(f), rebuilds and
// verifies V_f, renders it and writes the frame and its statistics.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <iostream>
#include <map>
#include <numeric>

#include "common/camera_path.hpp"
#include "common/cpu_time.hpp"
#include "common/progress.hpp"
#include "common/culling.hpp"
#include "common/error.hpp"
#include "common/hash.hpp"
#include "common/memory.hpp"
#include "common/gl/box_overlay.hpp"
#include "common/gl/context.hpp"
#include "common/gl/startup.hpp"
#include "common/gl/scene_renderer.hpp"
#include "protocol/cluster/switch_step.hpp"
#include "protocol/net/transport.hpp"
#include "protocol/visible_set.hpp"
#include "render_client/frame_output.hpp"
#include "render_client/options.hpp"
#include "render_client/viewer.hpp"

namespace occ {

namespace {

using Clock = std::chrono::steady_clock;
using net::Millis;

double ms_between(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double, std::milli>(b - a).count();
}

struct ClientFailure : std::runtime_error {
  using std::runtime_error::runtime_error;
};

class Client {
 public:
  explicit Client(const ClientOptions& o) : o_(o) {}

  int run() {
    if (o_.window) viewer_ = std::make_unique<Viewer>(o_);  // no display: fail before loading the scene
    g_ = start_scene_gl("render_client", o_.scene, o_.config.lod(), o_.gl, o_.width, o_.height, [&](const LoadedScene& ls) {
      if (viewer_)
        viewer_->start(ls.scene.bounds(), {o_.width, o_.height});  // path_ grows with next_camera()
      else
        path_ = load_camera_path(o_.path, ls.scene.bounds(), {o_.width, o_.height});
      if (!o_.save_path.empty()) save_camera_path(o_.save_path, path_);
    });
    if (viewer_ && o_.config.camera_mode == CameraMode::lockstep)
      std::cerr << "render_client: --window in lockstep camera mode: the view lags " << o_.lookahead
                << " frames; --camera-mode latest (on all three processes) is the interactive mode\n";
    leaf_count_ = 0;
    for (const HNode& n : g_.hierarchy().nodes()) leaf_count_ += n.leaf() && n.item_count > 0;
    total_triangles_ = g_.scene().triangle_count();
    connect();
    int code = 0;
    try {
      loop();
    } catch (const ClientFailure& e) {
      std::cerr << "error: render_client: " << e.what() << "\n";
      code = 1;
    }
    for (auto& c : nodes_)
      if (c) code ? c->close_with_error("render client failed") : c->close("render client done");
    summary();
    if (viewer_) viewer_->finish();  // writes --record
    return code;
  }

 private:
  void connect() {
    const wire::Hello mine = make_hello(wire::Role::render_client, 0, {o_.width, o_.height}, g_.fingerprint(),
                                        g_.hierarchy().params(), o_.config, "render_client");
    for (const std::string& text : o_.connect) {
      const net::Endpoint e = net::parse_endpoint("connect", text);
      auto conn = net::Connection::connect(e.host, e.port, Millis(o_.timeout_ms));
      if (!conn) throw std::runtime_error("cannot reach switch node at " + text + ": " + conn.error());
      net::PeerExpectation expect{wire::Role::switch_node, std::nullopt};
      expect.key = o_.key ? &*o_.key : nullptr;
      auto hello = net::handshake(*conn, mine, expect, Millis(o_.timeout_ms));
      if (const size_t busy = hello ? std::string::npos : hello.error().find(wire::kByeBusy); busy != std::string::npos)
        throw std::runtime_error("the cluster is busy: the switch node at " + text + " says " +
                                 hello.error().substr(busy + std::string_view(wire::kByeBusy).size()));
      if (!hello) throw std::runtime_error(hello.error());
      auto& slot = nodes_[hello->node_id & 1];
      if (slot) throw InputError("--connect: both addresses are switch node " + std::to_string(hello->node_id));
      slot = std::make_unique<net::Connection>(std::move(*conn));
    }
    if (!nodes_[0]) throw InputError("--connect: a single server must be node 0 (an occlusion_server)");
    std::cerr << "render_client: connected to switch node 0 (" << nodes_[0]->peer() << ")"
              << (nodes_[1] ? " and 1 (" + nodes_[1]->peer() + ")" : std::string(" only")) << "\n";
  }

  // Whether camera `number` exists (the next to send): on the path, or (--window) one more from
  // the viewer, appended to path_.
  bool have_camera(uint32_t number) { return number < path_.size() || (viewer_ && viewer_->next_camera(path_)); }

  void send_camera(uint32_t number) {
    sent_at_[number] = Clock::now();
    wire::Camera w = to_wire(number, path_[number], {o_.width, o_.height});
    for (int k = 0; k < 2; ++k)
      if (nodes_[k])
        if (auto err = nodes_[k]->send(w))
        throw ClientFailure("frame " + std::to_string(frame_) + ": sending camera " + std::to_string(number) +
                            " to switch node " + std::to_string(k) + " (" + nodes_[k]->peer() + "): " + *err);
  }

  net::Received receive_from(int node, uint32_t frame) {
    net::Received r = nodes_[node]->receive(Millis(o_.timeout_ms));
    if (r.ok()) return r;
    std::string what = r.status == net::Received::Status::timeout
                           ? "sent nothing for " + std::to_string(o_.timeout_ms) + " ms"
                           : (r.status == net::Received::Status::closed ? "closed the connection: " : "failed: ") + r.reason;
    throw ClientFailure("frame " + std::to_string(frame) + ": switch node " + std::to_string(node) + " (" +
                        nodes_[node]->peer() + ") " + what);
  }

  void loop() {
    const bool lockstep = o_.config.camera_mode == CameraMode::lockstep;
    FrameOutput out(o_.out, !o_.no_images,
                    {"frame", "camera", "hc_node", "visible", "added", "removed", "queries", "triangles",
                     "bytes_received", "hc_ms", "or_ms", "rvg_ms", "latency_ms", "frame_interval_ms",
                     "hc_cpu_ms", "or_cpu_ms", "or_tail_cpu_ms", "rvg_cpu_ms", "rvg_frame_cpu_ms", "or_tail_ms", "camera_gap"});
    VisibleSet visible(g_.renderables->count());
    // Front tracking is the switch's (both nodes): a single server sends plain diffs.
    const SwitchStep step(*g_.renderables, o_.config.lod_policy(o_.height), nodes_[1] && o_.config.tracks_fronts());
    DiffReceiver streams[2];
    uint32_t next_camera = 0;
    // `lookahead` cameras ahead, then one per frame received. Latest mode: the nodes take the
    // newest camera after the previous frame's, so at most `lookahead` frames are ever in flight.
    while (next_camera < uint32_t(o_.lookahead) && have_camera(next_camera)) send_camera(next_camera++);
    if (next_camera == 0) return;  // --window: the user quit before the first frame
    std::optional<uint32_t> prev_camera;  // the camera of the previous frame
    start_ = Clock::now();
    cpu_start_ = process_cpu_us();
    for (uint32_t frame = 0;; ++frame) {
      frame_ = frame;
      const int k = nodes_[1] ? int(hc_node_of_frame(frame)) : 0;  // one server: it does every frame
      // 1. The camera HC used for this frame comes first.
      net::Received r = receive_from(k, frame);
      auto* wcam = std::get_if<wire::Camera>(&r.message);
      if (!wcam) throw ClientFailure("frame " + std::to_string(frame) + ": switch node " + std::to_string(k) +
                                     " sent " + std::string(wire::type_name(wire::type_of(r.message))) + " before the camera");
      if (wcam->frame >= path_.size() || !sent_at_.count(wcam->frame))
        throw ClientFailure("frame " + std::to_string(frame) + ": switch node " + std::to_string(k) +
                            " used camera " + std::to_string(wcam->frame) + " that was never sent");
      if (lockstep && wcam->frame != frame)
        throw ClientFailure("frame " + std::to_string(frame) + ": lockstep, but switch node " + std::to_string(k) +
                            " used camera " + std::to_string(wcam->frame));
      if (prev_camera && wcam->frame <= *prev_camera)
        throw ClientFailure("frame " + std::to_string(frame) + ": switch node " + std::to_string(k) + " used camera " +
                            std::to_string(wcam->frame) + ", not newer than frame " + std::to_string(frame - 1) +
                            "'s camera " + std::to_string(*prev_camera));
      prev_camera = wcam->frame;
      // Cameras newer than this frame's that were already sent (latest mode: what a slow
      // render client lets pile up; lockstep: lookahead - 1).
      const uint32_t camera_gap = next_camera - 1 - wcam->frame;
      if (auto err = viewport_mismatch(*wcam, {o_.width, o_.height}))
        throw ClientFailure("frame " + std::to_string(frame) + ": switch node " + std::to_string(k) + " sent " + *err);
      const Camera cam = from_wire(*wcam);
      uint64_t bytes = r.wire_bytes;  // this frame's messages only (the io thread may read ahead)
      // Front tracking (switch_step.hpp): coarsen V_{f-1} for camera f exactly as both switch
      // nodes do; the diff is relative to the result, whose hash EndOfFrame.front_hash carries.
      const uint64_t expected_front = step.coarsen(visible, cam);
      // 2. Diff chunks, then EndOfFrame.
      bool cleared = false;
      wire::EndOfFrame eof;
      for (;;) {
        net::Received m = receive_from(k, frame);
        bytes += m.wire_bytes;
        if (o_.config.full_sets && !cleared) visible.clear();
        cleared = true;
        if (auto* d = std::get_if<wire::NodeDiff>(&m.message)) {
          if (auto err = streams[k].on_diff(visible, *d)) throw ClientFailure("desync with switch node " + std::to_string(k) + ": " + *err);
        } else if (auto* e = std::get_if<wire::EndOfFrame>(&m.message)) {
          if (e->frame != frame)
            throw ClientFailure("switch node " + std::to_string(k) + " ended frame " + std::to_string(e->frame) +
                                ", expected " + std::to_string(frame));
          if (auto err = streams[k].on_end_of_frame(visible, *e)) throw ClientFailure("desync with switch node " + std::to_string(k) + ": " + *err);
          if (e->front_hash != expected_front)
            throw ClientFailure("desync with switch node " + std::to_string(k) + ": frame " + std::to_string(frame) +
                                ": front hash " + hex(e->front_hash) + " from switch node " + std::to_string(k) + ", " +
                                hex(expected_front) + " here");
          eof = *e;
          break;
        } else {
          throw ClientFailure("frame " + std::to_string(frame) + ": unexpected " +
                              std::string(wire::type_name(wire::type_of(m.message))) + " from switch node " + std::to_string(k));
        }
      }
      // Keep the nodes busy: the next camera goes out before this frame is rendered.
      if (have_camera(next_camera)) send_camera(next_camera++);
      // 3. Render V_f with the camera of frame f.
      const Clock::time_point r0 = Clock::now();
      const uint64_t cpu_r0 = process_cpu_us();
      std::vector<uint32_t> ids(visible.ids().begin(), visible.ids().end());
      g_.renderer->begin_frame(cam, true);
      DrawStats st = g_.renderer->draw_renderables(*g_.renderables, ids, SceneRenderer::Mode::Shaded);
      g_.ctx->gl().Finish();
      const Clock::time_point shown = Clock::now();  // displayed; writing the PNG is not display
      const uint64_t cpu_shown = process_cpu_us();
      const double latency_ms = ms_between(sent_at_[wcam->frame], shown);
      Image image;
      if (out.writes_images() || viewer_) image = g_.ctx->read_rgba();
      if (out.writes_images()) out.write_frame(frame, image);  // the frame itself, never the overlay
      if (viewer_) {
        HudStats hud{latency_ms, visible.size(), leaf_count_, st.triangles, o_.config.pixel_error};
        if (viewer_->overlay()) {
          hud.occluded = long(draw_overlay(cam, ids));
          image = g_.ctx->read_rgba();
        }
        viewer_->show(cam, std::move(image), hud);
      }
      out.write_row({double(frame), double(wcam->frame), double(k), double(visible.size()), double(eof.total_added),
                     double(eof.total_removed), double(eof.queries), double(st.triangles), double(bytes),
                     eof.hc_us / 1000.0, eof.or_us / 1000.0, ms_between(r0, shown), latency_ms,
                     ms_between(frame_done_.empty() ? start_ : frame_done_.back(), shown), eof.hc_cpu_us / 1000.0,
                     eof.or_cpu_us / 1000.0, eof.or_tail_cpu_us / 1000.0, (cpu_shown - cpu_r0) / 1000.0,
                     (cpu_shown - (frame_done_.empty() ? cpu_start_ : cpu_prev_shown_)) / 1000.0,
                     eof.or_tail_us / 1000.0, double(camera_gap)});
      cpu_prev_shown_ = cpu_shown;
      frame_done_.push_back(shown);
      visible_sum_ += visible.size();
      bytes_sum_ += bytes;
      tri_sum_ += st.triangles;
      latency_.push_back(latency_ms);
      camera_gap_max_ = std::max(camera_gap_max_, camera_gap);
      hc_ms_ += eof.hc_us / 1000.0;
      or_ms_ += eof.or_us / 1000.0;
      rvg_ms_ += ms_between(r0, shown);
      if (frame % 10 == 9) progress("render_client: frame %u (camera %u/%zu)", frame + 1, wcam->frame + 1, path_.size());
      if (viewer_ && viewer_->quit()) break;
      if (wcam->frame + 1 == path_.size()) {  // every camera sent was used: the last frame, unless the viewer has more
        if (!have_camera(next_camera)) break;
        send_camera(next_camera++);
      }
    }
    progress_done();
  }

  // The O overlay: tints the boxes of the leaves in the frustum that occlusion culling removed
  // over the frame just drawn; returns how many.
  size_t draw_overlay(const Camera& cam, const std::vector<uint32_t>& visible_ids) {
    if (!overlay_) overlay_ = std::make_unique<BoxOverlay>(*g_.ctx);
    std::vector<uint32_t> nodes;
    for (uint32_t r : visible_ids) nodes.push_back(g_.renderables->node_of(r));
    std::vector<Aabb> boxes;
    for (uint32_t leaf : occluded_leaves(g_.hierarchy(), cam, nodes)) boxes.push_back(g_.hierarchy().node(leaf).box);
    overlay_->draw(cam, boxes);
    g_.ctx->gl().Finish();
    return boxes.size();
  }

  void summary() const {
    const size_t frames = frame_done_.size();
    if (frames == 0) return;
    std::vector<double> intervals;
    Clock::time_point prev = start_;
    for (auto t : frame_done_) {
      intervals.push_back(ms_between(prev, t));
      prev = t;
    }
    std::vector<double> sorted_iv = intervals, lat = latency_;
    std::sort(sorted_iv.begin(), sorted_iv.end());
    std::sort(lat.begin(), lat.end());
    const double wall_ms = ms_between(start_, frame_done_.back());
    const double mean_v = double(visible_sum_) / frames;
    std::printf(
        "summary: frames=%zu mean_fps=%.2f median_fps=%.2f mean_bytes_per_frame=%.0f mean_visible=%.1f "
        "leaves=%zu culled_pct=%.1f mean_triangles=%.0f triangles_culled_pct=%.1f latency_ms_mean=%.1f "
        "latency_ms_p95=%.1f hc_ms_mean=%.2f or_ms_mean=%.2f rvg_ms_mean=%.2f peak_rss_mb=%ld latency_frames=%.2f "
        "camera_gap_max=%u\n",
        frames, 1000.0 * frames / wall_ms, 1000.0 / sorted_iv[frames / 2], double(bytes_sum_) / frames, mean_v,
        leaf_count_, 100.0 * (1.0 - mean_v / std::max<size_t>(leaf_count_, 1)), double(tri_sum_) / frames,
        100.0 * (1.0 - double(tri_sum_) / frames / std::max<uint64_t>(total_triangles_, 1)),
        std::accumulate(lat.begin(), lat.end(), 0.0) / frames, lat[std::min(frames - 1, frames * 95 / 100)],
        hc_ms_ / frames, or_ms_ / frames, rvg_ms_ / frames, peak_rss_mb(),
        std::accumulate(lat.begin(), lat.end(), 0.0) / wall_ms, camera_gap_max_);
  }

  const ClientOptions& o_;
  std::unique_ptr<Viewer> viewer_;  // --window
  SceneGl g_;
  std::unique_ptr<BoxOverlay> overlay_;  // --window, O; after g_: its GL objects go before the context
  std::vector<Camera> path_;
  std::unique_ptr<net::Connection> nodes_[2];
  std::map<uint32_t, Clock::time_point> sent_at_;
  uint32_t frame_ = 0;  // the frame being received (for messages)
  Clock::time_point start_;
  uint64_t cpu_start_ = 0, cpu_prev_shown_ = 0;  // process CPU time (us)
  std::vector<Clock::time_point> frame_done_;
  std::vector<double> latency_;
  size_t leaf_count_ = 0;
  uint64_t total_triangles_ = 0, visible_sum_ = 0, bytes_sum_ = 0, tri_sum_ = 0;
  double hc_ms_ = 0, or_ms_ = 0, rvg_ms_ = 0;
  uint32_t camera_gap_max_ = 0;
};

}  // namespace

int run_cluster_client(const ClientOptions& o) { return Client(o).run(); }

}  // namespace occ
