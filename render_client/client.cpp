// The RVG display client (paper 4.5): sends cameras to both switch nodes, receives the camera
// actually used for frame f, the diff and EndOfFrame from the node doing HC, rebuilds and
// verifies V_f, renders it and writes the frame and its statistics. The parts: NodeLinks (the
// connections, faults, rejoin), FrameReceiver (cameras, resyncs, verified frames), FrameDrawer
// (one pass or two), FrameStats/RunStats (stats.csv and the summary); Client runs the frames.
#include <chrono>
#include <iostream>
#include <optional>

#include "common/camera_path.hpp"
#include "common/cpu_time.hpp"
#include "common/cull/culling.hpp"
#include "common/gl/context.hpp"
#include "common/gl/startup.hpp"
#include "common/progress.hpp"
#include "protocol/cluster/switch_step.hpp"
#include "protocol/visible_set.hpp"
#include "render_client/client_stats.hpp"
#include "render_client/frame_drawer.hpp"
#include "render_client/frame_output.hpp"
#include "render_client/frame_receiver.hpp"
#include "render_client/node_links.hpp"
#include "render_client/options.hpp"
#include "render_client/viewer.hpp"

namespace occ {

namespace {

using Clock = std::chrono::steady_clock;

double ms_between(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double, std::milli>(b - a).count();
}

class Client {
 public:
  explicit Client(const ClientOptions& o)
      : o_(o),
        links_(o),
        receiver_(o, links_, path_),
        gate_({.policy = o.occlusion_gate, .alternate_every = o.alternate_every}) {}

  int run() {
    start();
    int code = 0;
    try {
      loop();
    } catch (const ClientFailure& e) {
      std::cerr << "error: render_client: " << e.what() << "\n";
      code = 1;
    }
    links_.close(code != 0);
    summary();
    if (viewer_) viewer_->finish();  // writes OUT/path.csv
    return code;
  }

 private:
  // The scene, GL, the camera path (or the viewer), the drawer; then the switch nodes.
  void start() {
    if (o_.viewer()) viewer_ = std::make_unique<Viewer>(o_);  // no display: fail before loading the scene
    g_ = start_scene_gl("render_client", o_.scene, o_.config.lod(), o_.gl, o_.width, o_.height, [&](const LoadedScene& ls) {
      if (viewer_)
        viewer_->start(ls.scene.bounds(), {o_.width, o_.height});  // path_ grows with next_camera()
      else
        path_ = load_camera_path(o_.path, ls.scene.bounds(), {o_.width, o_.height});
      if (!o_.record.empty() && !viewer_) save_camera_path(o_.record, path_);
    });
    if (viewer_ && o_.config.camera_mode == CameraMode::lockstep)
      std::cerr << "render_client: --window in lockstep camera mode: the view lags " << o_.lookahead
                << " frames; --camera-mode latest (on all three processes) is the interactive mode\n";
    leaf_count_ = 0;
    for (const HNode& n : g_.hierarchy().nodes()) leaf_count_ += n.leaf() && n.item_count > 0;
    drawer_.emplace(o_, g_);
    links_.connect(make_hello(wire::Role::render_client, 0, {o_.width, o_.height}, g_.fingerprint(),
                              g_.hierarchy().params(), o_.config, "render_client", ""));
    if (!links_.is_switch()) gate_ = OcclusionGate({.policy = OcclusionGate::Policy::on});  // an occlusion_server always culls
  }

  // Whether camera `number` exists (the next to send): on the path, or (--window) one more from
  // the viewer, appended to path_.
  bool have_camera(uint32_t number) { return number < path_.size() || (viewer_ && viewer_->next_camera(path_)); }
  uint32_t next_camera() const { return receiver_.cameras_sent(); }
  void send_next_camera() { receiver_.send_camera(next_camera(), gate_.wire_occlusion(next_camera())); }

  // One frame as it goes through the steps below.
  struct Frame {
    uint32_t number = 0;
    std::optional<FrameReceiver::Served> served;
    FrameStats row;
    Camera cam;
    std::vector<uint32_t> ids;  // the set drawn: V_f, or the frustum set
    FrameDrawer::Drawn drawn;
    Clock::time_point shown;  // displayed; writing the PNG is not display
    uint64_t cpu_shown = 0;
  };

  void loop() {
    out_.emplace(o_.out, !o_.no_images, FrameStats::columns());
    if (o_.item_buffer) out_->write_item_space(g_.hierarchy());
    VisibleSet visible(g_.renderables->count());
    // Front tracking is the switch's (both nodes, or one of them alone after a failure): a
    // single occlusion_server sends plain diffs.
    const SwitchStep step(*g_.renderables, o_.config.lod_policy(o_.height), links_.is_switch() && o_.config.front_tracking);
    // `lookahead` cameras ahead, then one per frame received. Latest mode: the nodes take the
    // newest camera after the previous frame's, so at most `lookahead` frames are ever in flight.
    while (next_camera() < uint32_t(o_.lookahead) && have_camera(next_camera())) send_next_camera();
    if (next_camera() == 0) return;  // --window: the user quit before the first frame
    stats_.start(Clock::now(), process_cpu_us());
    for (uint32_t number = 0;; ++number) {
      Frame f;
      f.number = number;
      receiver_.resync_if_needed(number, visible);
      receive(f, visible, step);
      draw(f, visible);
      show(f);
      record(f);
      if (number % 10 == 9)
        progress("render_client: frame %u (camera %u/%zu)", number + 1, f.row.camera + 1, path_.size());
      if (!more_frames(f)) break;
    }
    progress_done();
  }

  // Frame f's set from the node serving it (none: frustum culling here), its camera and mode;
  // the next camera goes out before the frame is drawn, to keep the nodes busy.
  void receive(Frame& f, VisibleSet& visible, const SwitchStep& step) {
    const int k = links_.server_of(f.number);
    const Clock::time_point w0 = Clock::now();
    if (k >= 0) f.served = receiver_.receive(k, f.number, visible, step);
    f.row.wait_ms = ms_between(w0, Clock::now());
    FrameStats& row = f.row;
    row.frame = f.number;
    if (f.served) {
      row.mode = receiver_.resynced_at(f.number) ? Mode::resync : links_.members() == 2 ? Mode::switch_ : Mode::single;
      row.camera = f.served->wcam.frame;
      row.hc_node = k;
    } else {  // lockstep: camera `frame` (sent: lookahead >= 1); latest: the newest camera sent
      row.mode = Mode::frustum;
      row.camera = o_.config.camera_mode == CameraMode::lockstep ? f.number : next_camera() - 1;
    }
    receiver_.used_camera(row.camera);
    // Cameras newer than this frame's that were already sent (latest mode: what a slow render
    // client lets pile up; lockstep: lookahead - 1).
    row.camera_gap = next_camera() - 1 - row.camera;
    if (have_camera(next_camera())) send_next_camera();
    f.cam = f.served ? from_wire(f.served->wcam) : path_[row.camera];
  }

  // 3. Render V_f (or the frustum set) with the camera of frame f.
  void draw(Frame& f, const VisibleSet& visible) {
    const Clock::time_point r0 = Clock::now();
    const uint64_t cpu_r0 = process_cpu_us();
    const GeometryPool* pool = g_.renderer->geometry_pool();
    const GeometryPool::Stats before = pool ? pool->stats() : GeometryPool::Stats{};
    if (f.served)
      f.ids.assign(visible.ids().begin(), visible.ids().end());
    else
      f.ids = frustum_cull(g_.hierarchy(), f.cam);  // leaves at full detail: renderable id = node id
    // A frustum set (the switch culled without occlusion, or no node serves) is culled here,
    // in two passes against the frame's own depth, where that pays (two_pass.hpp).
    f.drawn = drawer_->draw(f.cam, f.ids, !f.served || !f.served->wcam.occlusion, gate_.measuring_without());
    f.shown = Clock::now();
    f.cpu_shown = process_cpu_us();
    f.row.rvg_ms = ms_between(r0, f.shown);
    f.row.rvg_cpu_ms = (f.cpu_shown - cpu_r0) / 1000.0;
    if (pool) {
      f.row.geometry_waits = pool->stats().uploads - before.uploads;
      f.row.geometry_wait_ms = pool->stats().upload_ms - before.upload_ms;
    }
  }

  // The frame to --out and the window.
  void show(Frame& f) {
    f.row.latency_ms = ms_between(receiver_.sent_at(f.row.camera), f.shown);
    Image image;
    if (out_->writes_images() || viewer_) image = g_.ctx->read_rgba();
    if (out_->writes_images()) out_->write_frame(f.number, image);  // the frame itself, never the overlay
    if (!viewer_ && !o_.item_buffer) return;
    // What was drawn: the set, less what the two passes proved hidden (also for the overlay).
    const std::vector<uint32_t> shown_ids = drawer_->drawn_ids(f.drawn, f.ids);
    if (viewer_) show_in_window(f, shown_ids, std::move(image));
    // Last: it draws over the frame buffer.
    if (o_.item_buffer) {
      const Image ids = drawer_->item_buffer(f.cam, shown_ids);
      out_->write_items(f.number, ids, drawer_->depth());
    }
  }

  void show_in_window(const Frame& f, const std::vector<uint32_t>& shown_ids, Image image) {
    const Mode mode = f.row.mode;
    HudStats hud{f.row.latency_ms, shown_ids.size(), leaf_count_, f.drawn.st.triangles, o_.config.pixel_error, -1,
                 mode == Mode::single    ? "degraded: one switch node"
                 : mode == Mode::frustum ? "degraded: frustum culling"
                 : f.served && !f.served->wcam.occlusion
                     ? (f.drawn.two_pass ? "switch, no occlusion (culled here)" : "switch, no occlusion (does not pay here)")
                     : mode_name(mode),
                 f.row.camera};
    if (viewer_->overlay()) {
      hud.occluded = long(drawer_->draw_overlay(f.cam, shown_ids));
      image = g_.ctx->read_rgba();
    }
    viewer_->show(f.cam, std::move(image), hud);
  }

  // The frame's stats.csv row and what the gates learn from it.
  void record(Frame& f) {
    FrameStats& row = f.row;
    const wire::EndOfFrame eof = f.served ? f.served->eof : wire::EndOfFrame{};
    row.visible = f.ids.size();
    row.added = eof.total_added;
    row.removed = eof.total_removed;
    row.queries = eof.queries;
    row.triangles = f.drawn.st.triangles;
    row.bytes_received = f.served ? f.served->bytes : 0;
    row.full_set_bytes =
        f.served ? f.served->bytes - f.served->diff_bytes + wire::full_set_wire_bytes(f.served->eof.visible_count) : 0;
    row.hc_ms = eof.hc_us / 1000.0;
    row.or_ms = eof.or_us / 1000.0;
    row.frame_interval_ms = stats_.interval_ms(f.shown);
    row.hc_cpu_ms = eof.hc_cpu_us / 1000.0;
    row.or_cpu_ms = eof.or_cpu_us / 1000.0;
    row.or_tail_cpu_ms = eof.or_tail_cpu_us / 1000.0;
    row.rvg_frame_cpu_ms = stats_.cpu_since_last_us(f.cpu_shown) / 1000.0;
    row.or_tail_ms = eof.or_tail_us / 1000.0;
    row.occlusion = f.served ? f.served->wcam.occlusion : 0;
    row.two_pass = f.drawn.two_pass ? 1 + f.drawn.tp.redrawn : 0;
    row.hidden_here = f.drawn.tp.hidden;
    row.write(*out_);
    drawer_->measured(f.drawn, row.rvg_ms);
    if (row.mode == Mode::switch_) {
      std::optional<uint64_t> frustum;
      if (!row.occlusion)
        frustum = f.drawn.set_triangles();
      else if (gate_.wants_frustum_triangles())
        frustum = frustum_triangles(f.cam);
      gate_.frame(row.occlusion != 0, row.frame_interval_ms, row.triangles, frustum, f.drawn.representative);
    }
    if (stats_.frames() == 0)
      std::fprintf(stderr, "render_client: first frame shown %.1f s after the process started (wall clock %.3f)\n",
                   process_age_s(),
                   std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count());
    stats_.add(row, f.shown, f.cpu_shown);
  }

  // Whether another frame follows: not when the user quit, or every camera sent was used and
  // there is none more (the viewer may have more).
  bool more_frames(const Frame& f) {
    if (viewer_ && viewer_->quit()) return false;
    if (f.row.camera + 1 == path_.size()) {
      if (!have_camera(next_camera())) return false;
      send_next_camera();
    }
    return true;
  }

  // The triangles of the frustum set at the chosen LODs: what frames without occlusion draw.
  uint64_t frustum_triangles(const Camera& cam) const {
    FrustumOnlyQueries all;
    const LodSelector sel = o_.config.lod_policy(o_.height).selector(*g_.renderables, cam);
    uint64_t t = 0;
    for (uint32_t id : hardware_cull_lod(g_.hierarchy(), cam, all, sel)) t += g_.renderables->triangles(id);
    return t;
  }

  void summary() const {
    if (stats_.frames() == 0) return;
    const std::string backends[2] = {links_.occlusion_backend(0), links_.occlusion_backend(1)};
    stats_.print_table(leaf_count_, g_.scene().triangle_count(), backends);
    stats_.print(leaf_count_, g_.scene().triangle_count(), receiver_.resyncs(), gate_.frames_off());
    print_geometry_line(stdout, "render_client", g_.renderer->geometry_pool());
    if (links_.is_switch() && o_.occlusion_gate == OcclusionGate::Policy::automatic)
      std::cerr << "render_client: occlusion gate: " << gate_.describe() << " (frame interval)\n";
    drawer_->print_summary();
  }

  const ClientOptions& o_;
  std::unique_ptr<Viewer> viewer_;  // --window, --web
  SceneGl g_;
  std::optional<FrameDrawer> drawer_;  // after g_: its GL objects go before the context
  std::vector<Camera> path_;
  NodeLinks links_;
  FrameReceiver receiver_;
  OcclusionGate gate_;  // occlusion only where it pays (--occlusion)
  std::optional<FrameOutput> out_;
  RunStats stats_;
  size_t leaf_count_ = 0;
};

}  // namespace

int run_cluster_client(const ClientOptions& o) { return Client(o).run(); }

}  // namespace occ
