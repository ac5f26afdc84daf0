// The RVG display client (paper 4.5): sends cameras to both switch nodes, receives the camera
// actually used for frame f, the diff and EndOfFrame from the node doing HC(f), rebuilds and
// verifies V_f, renders it and writes the frame and its statistics.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <mutex>
#include <optional>
#include <thread>
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
#include "common/gl/two_pass.hpp"
#include "render_client/viewer.hpp"

namespace occ {

namespace {

using Clock = std::chrono::steady_clock;
using net::Millis;

// How often a client waiting for one switch node looks at the other node's connection.
constexpr Millis kWatchOther{20};

double ms_between(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double, std::milli>(b - a).count();
}

struct ClientFailure : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// Switch node `node` failed (died, stalled past --timeout-ms, sent something invalid).
struct NodeFault : std::runtime_error {
  NodeFault(int n, const std::string& what) : std::runtime_error(what), node(n) {}
  int node;
};

// How a frame's visible set was found (stats.csv column `mode`, the window's HUD):
//   switch   the occlusion switch (both nodes), as designed
//   resync   the first frame after a resync (empty sets everywhere: the node's HC sends the full set)
//   single   one switch node serves alone (OR and HC of every frame), the other being down
//   frustum  no node serves: this client's own hierarchical frustum culling
// single and frustum are the degraded modes. Every one is conservative: a frame is drawn from a
// set computed for its own camera, never from a stale one.
enum class Mode { switch_, resync, single, frustum };
const char* mode_name(Mode m) {
  switch (m) {
    case Mode::switch_: return "switch";
    case Mode::resync: return "resync";
    case Mode::single: return "single";
    case Mode::frustum: return "frustum";
  }
  return "?";
}

// One switch node as the client sees it.
struct NodeLink {
  std::unique_ptr<net::Connection> conn;  // null: down (the rejoiner looks for it)
  std::string address;                    // its --connect
  uint32_t await_epoch = 0;               // its messages are stale until it echoes this Resync (0: none)
};

class Client {
 public:
  explicit Client(const ClientOptions& o)
      : o_(o), gate_({.policy = o.occlusion_gate}), two_pass_gate_({.policy = o.two_pass, .trial_after = 3}) {}

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
    two_pass_ = std::make_unique<TwoPassDrawer>(*g_.ctx, *g_.renderer, g_.hierarchy(), *g_.renderables);
    connect();
    if (!switch_) gate_ = OcclusionGate({.policy = OcclusionGate::Policy::on});  // an occlusion_server always culls
    int code = 0;
    try {
      loop();
    } catch (const ClientFailure& e) {
      std::cerr << "error: render_client: " << e.what() << "\n";
      code = 1;
    }
    stop_rejoiner();
    for (auto& n : nodes_)
      if (n.conn) code ? n.conn->close_with_error("render client failed") : n.conn->close("render client done");
    summary();
    if (viewer_) viewer_->finish();  // writes --record
    return code;
  }

 private:
  void connect() {
    mine_ = make_hello(wire::Role::render_client, 0, {o_.width, o_.height}, g_.fingerprint(), g_.hierarchy().params(),
                       o_.config, "render_client");
    for (const std::string& text : o_.connect) {
      const net::Endpoint e = net::parse_endpoint("connect", text);
      auto conn = net::Connection::connect(e.host, e.port, Millis(o_.timeout_ms));
      if (!conn) throw std::runtime_error("cannot reach switch node at " + text + ": " + conn.error());
      net::PeerExpectation expect{wire::Role::switch_node, std::nullopt};
      expect.key = o_.key ? &*o_.key : nullptr;
      auto hello = net::handshake(*conn, mine_, expect, Millis(o_.timeout_ms));
      if (!hello && hello.error_kind() == ErrorKind::busy)
        throw std::runtime_error("the cluster is busy: the switch node at " + text + " refused us: " + hello.error());
      if (!hello) throw std::runtime_error(hello.error());
      NodeLink& slot = nodes_[hello->node_id & 1];
      if (slot.conn) throw InputError("--connect: both addresses are switch node " + std::to_string(hello->node_id));
      slot.conn = std::make_unique<net::Connection>(std::move(*conn));
      slot.address = text;
    }
    if (!nodes_[0].conn) throw InputError("--connect: a single server must be node 0 (an occlusion_server)");
    switch_ = bool(nodes_[1].conn);
    std::cerr << "render_client: connected to switch node 0 (" << nodes_[0].conn->peer() << ")"
              << (switch_ ? " and 1 (" + nodes_[1].conn->peer() + ")" : std::string(" only")) << "\n";
  }

  std::string node_name(int k) const {
    return "switch node " + std::to_string(k) + " (" + (nodes_[k].conn ? nodes_[k].conn->peer() : nodes_[k].address) + ")";
  }
  int members() const { return bool(nodes_[0].conn) + bool(nodes_[1].conn); }
  // The node serving frame `frame`: the switch's HC node, the one left, or none (-1).
  int server_of(uint32_t frame) const {
    if (nodes_[0].conn && nodes_[1].conn) return int(hc_node_of_frame(frame));
    return nodes_[0].conn ? 0 : nodes_[1].conn ? 1 : -1;
  }

  // Whether camera `number` exists (the next to send): on the path, or (--window) one more from
  // the viewer, appended to path_.
  bool have_camera(uint32_t number) { return number < path_.size() || (viewer_ && viewer_->next_camera(path_)); }

  // To every node that is up; a node that cannot take it is dropped (or, --on-node-failure exit,
  // the run ends).
  void send_camera(uint32_t number) {
    sent_at_[number] = Clock::now();
    if (cam_occlusion_.size() <= number) cam_occlusion_.resize(number + 1, 1);
    cam_occlusion_[number] = gate_.wire_occlusion(number);  // the same for both nodes and for resends
    for (int k = 0; k < 2; ++k)
      if (nodes_[k].conn) send_camera_to(k, number);
  }
  void send_camera_to(int k, uint32_t number) {
    const wire::Camera w = to_wire(number, path_[number], {o_.width, o_.height}, cam_occlusion_.at(number));
    if (auto err = nodes_[k].conn->send(w))
      drop(k, "frame " + std::to_string(frame_) + ": sending camera " + std::to_string(number) + " to " + node_name(k) +
                  ": " + *err);
  }

  // The next message from switch node `node`, waiting up to --timeout-ms. Meanwhile the other
  // node's connection is watched: when it ends (the node died: reset or EOF, or it said Bye), the
  // other node is dropped at once (NodeFault for it), without waiting out the timeout. The node
  // waited for may be waiting for the dead one itself: a node killed between queuing its last
  // frame to this client and to its peer leaves that frame complete here but not on the peer,
  // which then drops its peer and waits for this client's resync, while this client waited for
  // the peer's next frame; both waited out --timeout-ms and the client dropped the healthy node too.
  net::Received receive_from(int node, uint32_t frame) {
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
  std::string end_of(int k) {
    for (;;) {
      net::Received r = nodes_[k].conn->receive(Millis(0));
      if (r.ok()) continue;
      if (r.status == net::Received::Status::closed) return "closed the connection: " + r.reason;
      return "failed: " + (r.status == net::Received::Status::error ? r.reason : std::string("connection ended"));
    }
  }

  // A failed node: with --on-node-failure exit the run ends here (exit 1). Otherwise the node is
  // closed, the next frame starts over without it (resync) and the rejoiner waits for it.
  void drop(int k, const std::string& what) {
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
  void want_rejoin(int k) {
    {
      std::lock_guard<std::mutex> lock(rejoin_mu_);
      wanted_[k] = true;
    }
    if (!rejoiner_.joinable()) rejoiner_ = std::thread([this] { rejoin_loop(); });
  }
  void rejoin_loop() {
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
        auto conn = net::Connection::connect(e.host, e.port, Millis(20));
        if (!conn) continue;  // nothing listens there (yet)
        net::PeerExpectation expect{wire::Role::switch_node, uint8_t(k)};
        expect.key = o_.key ? &*o_.key : nullptr;  // a keyed cluster takes back only a node with the key
        auto hello = net::handshake(*conn, mine_, expect, Millis(std::min(o_.timeout_ms, 5000)));
        if (!hello) {  // logged by the connection; a stranger there is not asked again at once
          next_try[k] = Clock::now() + backoff[k];
          backoff[k] = std::min(backoff[k] * 2, Millis(5000));
          continue;
        }
        std::lock_guard<std::mutex> lock(rejoin_mu_);
        rejoined_[k] = std::make_unique<net::Connection>(std::move(*conn));
        wanted_[k] = false;
        backoff[k] = Millis(200);
      }
    }
  }
  void stop_rejoiner() {
    stop_rejoin_ = true;
    if (rejoiner_.joinable()) rejoiner_.join();
    for (auto& c : rejoined_)
      if (c) c->close("render client done");
  }
  // Nodes the rejoiner brought back since the last frame.
  void take_rejoined(uint32_t frame) {
    std::lock_guard<std::mutex> lock(rejoin_mu_);
    for (int k = 0; k < 2; ++k) {
      if (!rejoined_[k]) continue;
      nodes_[k].conn = std::move(rejoined_[k]);
      std::cerr << "render_client: frame " << frame << ": " << node_name(k) << " is back\n";
      need_resync_ = true;
    }
  }

  // Everyone starts over at `frame` with empty sets (wire.hpp Resync): the switch if both nodes
  // are up, the one that is up alone, or nobody (frustum culling here). Nodes that fail to take it
  // are dropped, and the caller calls again.
  void resync(uint32_t frame, VisibleSet& visible) {
    need_resync_ = false;
    visible.clear();
    for (auto& s : streams_) s = DiffReceiver{};
    resync_frame_.reset();
    const int n = members();
    if (n == 0) {
      std::cerr << "render_client: frame " << frame << ": no switch node: frustum culling in the render client\n";
      return;
    }
    if (!switch_) return;  // an occlusion_server is never resynchronised (its failure leaves frustum culling)
    ++epoch_;
    for (int k = 0; k < 2; ++k) {
      if (!nodes_[k].conn) continue;
      nodes_[k].await_epoch = epoch_;
      if (auto err = nodes_[k].conn->send(wire::Resync{frame, epoch_, uint32_t(n)})) {
        drop(k, "frame " + std::to_string(frame) + ": sending the resync to " + node_name(k) + ": " + *err);
        return;
      }
      // The cameras it may lack (a restarted node has none; the other may have used them).
      if (o_.config.camera_mode == CameraMode::lockstep) {
        for (uint32_t c = frame; c < next_camera_ && nodes_[k].conn; ++c) send_camera_to(k, c);
      } else if (next_camera_ > 0) {
        send_camera_to(k, next_camera_ - 1);
      }
      if (!nodes_[k].conn) return;  // dropped: need_resync_ is set again
    }
    resync_frame_ = frame;
    ++resyncs_;
    std::cerr << "render_client: frame " << frame << ": resync " << epoch_ << ": "
              << (n == 2 ? std::string("the switch resumes (switch nodes 0 and 1)")
                         : node_name(server_of(frame)) + " serves alone")
              << ", from a full visible set\n";
  }

  // Frame `frame` from switch node k: its camera, the diff, EndOfFrame; `visible` becomes V_f.
  // Throws NodeFault.
  struct Served {
    wire::Camera wcam;
    wire::EndOfFrame eof;
    uint64_t bytes = 0;
  };
  Served receive_frame(int k, uint32_t frame, VisibleSet& visible, const SwitchStep& step) {
    const bool lockstep = o_.config.camera_mode == CameraMode::lockstep;
    const std::string f = "frame " + std::to_string(frame) + ": ";
    auto fault = [&](const std::string& what) { return NodeFault(k, f + node_name(k) + " " + what); };
    // 0. What it sent before acknowledging the last resync is stale.
    net::Received r = receive_from(k, frame);
    while (nodes_[k].await_epoch) {
      if (auto* rs = std::get_if<wire::Resync>(&r.message); rs && rs->epoch == nodes_[k].await_epoch) {
        if (!resync_frame_ || rs->frame != *resync_frame_ || rs->nodes != uint32_t(members()))
          throw fault("acknowledged resync " + std::to_string(rs->epoch) + " for frame " + std::to_string(rs->frame) +
                      " with " + std::to_string(rs->nodes) + " nodes");
        nodes_[k].await_epoch = 0;
      }
      r = receive_from(k, frame);
    }
    // 1. The camera HC used for this frame comes first.
    auto* wcam = std::get_if<wire::Camera>(&r.message);
    if (!wcam) throw fault("sent " + std::string(wire::type_name(wire::type_of(r.message))) + " before the camera");
    if (wcam->frame >= path_.size() || !sent_at_.count(wcam->frame))
      throw fault("used camera " + std::to_string(wcam->frame) + " that was never sent");
    if (lockstep && wcam->frame != frame) throw fault("used camera " + std::to_string(wcam->frame) + " (lockstep)");
    if (prev_camera_ && wcam->frame <= *prev_camera_)
      throw fault("used camera " + std::to_string(wcam->frame) + ", not newer than frame " + std::to_string(frame - 1) +
                  "'s camera " + std::to_string(*prev_camera_));
    if (auto err = viewport_mismatch(*wcam, {o_.width, o_.height})) throw fault("sent " + *err);
    Served s{*wcam, {}, r.wire_bytes};  // this frame's messages only (the io thread may read ahead)
    // Front tracking (switch_step.hpp): coarsen V_{f-1} for camera f exactly as the switch
    // nodes do; the diff is relative to the result, whose hash EndOfFrame.front_hash carries.
    const uint64_t expected_front = step.coarsen(visible, from_wire(*wcam));
    // 2. Diff chunks, then EndOfFrame.
    bool cleared = false;
    for (;;) {
      net::Received m = receive_from(k, frame);
      s.bytes += m.wire_bytes;
      if (o_.config.full_sets && !cleared) visible.clear();
      cleared = true;
      if (auto* d = std::get_if<wire::NodeDiff>(&m.message)) {
        if (auto err = streams_[k].on_diff(visible, *d)) throw fault("desync: " + *err);
      } else if (auto* e = std::get_if<wire::EndOfFrame>(&m.message)) {
        if (e->frame != frame) throw fault("ended frame " + std::to_string(e->frame));
        if (auto err = streams_[k].on_end_of_frame(visible, *e)) throw fault("desync: " + *err);
        if (e->front_hash != expected_front)
          throw fault("desync: front hash " + hex(e->front_hash) + " from the node, " + hex(expected_front) + " here");
        s.eof = *e;
        return s;
      } else {
        throw fault("sent an unexpected " + std::string(wire::type_name(wire::type_of(m.message))));
      }
    }
  }

  void loop() {
    const bool lockstep = o_.config.camera_mode == CameraMode::lockstep;
    FrameOutput out(o_.out, !o_.no_images,
                    {"frame", "camera", "hc_node", "visible", "added", "removed", "queries", "triangles",
                     "bytes_received", "hc_ms", "or_ms", "rvg_ms", "latency_ms", "frame_interval_ms",
                     "hc_cpu_ms", "or_cpu_ms", "or_tail_cpu_ms", "rvg_cpu_ms", "rvg_frame_cpu_ms", "or_tail_ms",
                     "camera_gap", "occlusion", "two_pass", "hidden_here", "mode"});
    VisibleSet visible(g_.renderables->count());
    // Front tracking is the switch's (both nodes, or one of them alone after a failure): a
    // single occlusion_server sends plain diffs.
    const SwitchStep step(*g_.renderables, o_.config.lod_policy(o_.height), switch_ && o_.config.tracks_fronts());
    // `lookahead` cameras ahead, then one per frame received. Latest mode: the nodes take the
    // newest camera after the previous frame's, so at most `lookahead` frames are ever in flight.
    while (next_camera_ < uint32_t(o_.lookahead) && have_camera(next_camera_)) send_camera(next_camera_++);
    if (next_camera_ == 0) return;  // --window: the user quit before the first frame
    start_ = Clock::now();
    cpu_start_ = process_cpu_us();
    for (uint32_t frame = 0;; ++frame) {
      frame_ = frame;
      take_rejoined(frame);
      while (need_resync_) resync(frame, visible);
      const int k = server_of(frame);
      std::optional<Served> served;
      if (k >= 0) {
        try {
          served = receive_frame(k, frame, visible, step);
        } catch (const NodeFault& e) {
          drop(e.node, e.what());
        }
      }
      Mode mode = Mode::frustum;
      uint32_t cam_number = 0;
      if (served) {
        mode = resync_frame_ == frame ? Mode::resync : members() == 2 ? Mode::switch_ : Mode::single;
        cam_number = served->wcam.frame;
      } else {  // lockstep: camera `frame` (sent: lookahead >= 1); latest: the newest camera sent
        cam_number = lockstep ? frame : next_camera_ - 1;
      }
      prev_camera_ = cam_number;
      // Cameras newer than this frame's that were already sent (latest mode: what a slow
      // render client lets pile up; lockstep: lookahead - 1).
      const uint32_t camera_gap = next_camera_ - 1 - cam_number;
      // Keep the nodes busy: the next camera goes out before this frame is rendered.
      if (have_camera(next_camera_)) send_camera(next_camera_++);
      const Camera cam = served ? from_wire(served->wcam) : path_[cam_number];
      // 3. Render V_f (or the frustum set) with the camera of frame f.
      const Clock::time_point r0 = Clock::now();
      const uint64_t cpu_r0 = process_cpu_us();
      std::vector<uint32_t> ids;
      if (served)
        ids.assign(visible.ids().begin(), visible.ids().end());
      else
        ids = frustum_cull(g_.hierarchy(), cam);  // leaves at full detail: renderable id = node id
      // A frustum set (the switch culled without occlusion, or no node serves) is culled here,
      // in two passes against the frame's own depth, where that pays (two_pass.hpp).
      const bool frustum_set = !served || !served->wcam.occlusion;
      const bool two_pass = frustum_set && two_pass_gate_.occlusion(two_pass_frames_);
      DrawStats st;
      TwoPassDrawer::Frame tp;
      if (two_pass) {
        // After frames the switch culled, pass 1 starts from its last visible set; after frames
        // drawn in one pass, from everything.
        if (!two_pass_last_) switch_culled_last_ ? two_pass_->seed(last_visible_) : two_pass_->forget();
        tp = two_pass_->draw(cam, ids);
        st = tp.drawn;
        two_pass_redrawn_ += tp.redrawn;
        ++two_pass_used_;
      } else {
        g_.renderer->begin_frame(cam, true);
        st = g_.renderer->draw_renderables(*g_.renderables, ids, SceneRenderer::Mode::Shaded);
        g_.ctx->gl().Finish();
      }
      two_pass_last_ = two_pass;
      switch_culled_last_ = !frustum_set;
      if (!frustum_set) last_visible_ = ids;
      const Clock::time_point shown = Clock::now();  // displayed; writing the PNG is not display
      const uint64_t cpu_shown = process_cpu_us();
      const double latency_ms = ms_between(sent_at_[cam_number], shown);
      Image image;
      if (out.writes_images() || viewer_) image = g_.ctx->read_rgba();
      if (out.writes_images()) out.write_frame(frame, image);  // the frame itself, never the overlay
      if (viewer_) {
        // What was drawn: the set, less what the two passes proved hidden (also for the overlay).
        std::vector<uint32_t> drawn_ids;
        if (two_pass) two_pass_->drawn_ids(drawn_ids);
        const std::vector<uint32_t>& shown_ids = two_pass ? drawn_ids : ids;
        HudStats hud{latency_ms, shown_ids.size(), leaf_count_, st.triangles, o_.config.pixel_error, -1,
                     mode == Mode::single    ? "degraded: one switch node"
                     : mode == Mode::frustum ? "degraded: frustum culling"
                     : served && !served->wcam.occlusion
                         ? (two_pass ? "switch, no occlusion (culled here)" : "switch, no occlusion (does not pay here)")
                         : mode_name(mode)};
        if (viewer_->overlay()) {
          hud.occluded = long(draw_overlay(cam, shown_ids));
          image = g_.ctx->read_rgba();
        }
        viewer_->show(cam, std::move(image), hud);
      }
      const wire::EndOfFrame eof = served ? served->eof : wire::EndOfFrame{};
      const double interval_ms = ms_between(frame_done_.empty() ? start_ : frame_done_.back(), shown);
      const uint64_t bytes = served ? served->bytes : 0;
      out.write_row({double(frame), double(cam_number), double(served ? k : -1), double(ids.size()),
                     double(eof.total_added), double(eof.total_removed), double(eof.queries), double(st.triangles),
                     double(bytes), eof.hc_us / 1000.0, eof.or_us / 1000.0, ms_between(r0, shown), latency_ms,
                     interval_ms, eof.hc_cpu_us / 1000.0,
                     eof.or_cpu_us / 1000.0, eof.or_tail_cpu_us / 1000.0, (cpu_shown - cpu_r0) / 1000.0,
                     (cpu_shown - (frame_done_.empty() ? cpu_start_ : cpu_prev_shown_)) / 1000.0,
                     eof.or_tail_us / 1000.0, double(camera_gap), double(served ? served->wcam.occlusion : 0),
                     double(two_pass ? 1 + tp.redrawn : 0), double(tp.hidden)},
                    {mode_name(mode)});
      ++mode_frames_[int(mode)];
      if (frustum_set) {
        const uint64_t set_triangles = two_pass ? tp.set_triangles : st.triangles;
        two_pass_gate_.frame(two_pass, ms_between(r0, shown), st.triangles, set_triangles);
        ++two_pass_frames_;
      }
      if (mode == Mode::switch_) {
        std::optional<uint64_t> frustum;
        if (gate_.wants_frustum_triangles()) frustum = frustum_triangles(cam);
        gate_.frame(served->wcam.occlusion != 0, interval_ms, st.triangles, frustum);
      }
      cpu_prev_shown_ = cpu_shown;
      frame_done_.push_back(shown);
      visible_sum_ += ids.size();
      bytes_sum_ += bytes;
      tri_sum_ += st.triangles;
      latency_.push_back(latency_ms);
      camera_gap_max_ = std::max(camera_gap_max_, camera_gap);
      hc_ms_ += eof.hc_us / 1000.0;
      or_ms_ += eof.or_us / 1000.0;
      rvg_ms_ += ms_between(r0, shown);
      if (frame % 10 == 9) progress("render_client: frame %u (camera %u/%zu)", frame + 1, cam_number + 1, path_.size());
      if (viewer_ && viewer_->quit()) break;
      if (cam_number + 1 == path_.size()) {  // every camera sent was used: the last frame, unless the viewer has more
        if (!have_camera(next_camera_)) break;
        send_camera(next_camera_++);
      }
    }
    progress_done();
  }

  // The triangles of the frustum set at the chosen LODs: what frames without occlusion draw.
  uint64_t frustum_triangles(const Camera& cam) const {
    FrustumOnlyQueries all;
    const LodSelector sel = o_.config.lod_policy(o_.height).selector(*g_.renderables, cam);
    uint64_t t = 0;
    for (uint32_t id : hardware_cull_lod(g_.hierarchy(), cam, all, sel)) t += g_.renderables->triangles(id);
    return t;
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
        "camera_gap_max=%u frames_without_occlusion=%u\n",
        frames, 1000.0 * frames / wall_ms, 1000.0 / sorted_iv[frames / 2], double(bytes_sum_) / frames, mean_v,
        leaf_count_, 100.0 * (1.0 - mean_v / std::max<size_t>(leaf_count_, 1)), double(tri_sum_) / frames,
        100.0 * (1.0 - double(tri_sum_) / frames / std::max<uint64_t>(total_triangles_, 1)),
        std::accumulate(lat.begin(), lat.end(), 0.0) / frames, lat[std::min(frames - 1, frames * 95 / 100)],
        hc_ms_ / frames, or_ms_ / frames, rvg_ms_ / frames, peak_rss_mb(),
        std::accumulate(lat.begin(), lat.end(), 0.0) / wall_ms, camera_gap_max_, gate_.frames_off());
    if (switch_ && o_.occlusion_gate == OcclusionGate::Policy::automatic)
      std::cerr << "render_client: occlusion gate: " << gate_.describe() << " (frame interval)\n";
    if (two_pass_frames_ > 0)
      std::cerr << "render_client: " << two_pass_frames_ << " frames of frustum sets, " << two_pass_used_
                << " of them culled here in two passes (" << two_pass_redrawn_
                << " drawn again for a depth tie); two-pass gate: " << two_pass_gate_.describe("two passes") << "\n";
    if (frames != mode_frames_[int(Mode::switch_)])
      std::printf("modes: switch=%zu resync=%zu single=%zu frustum=%zu resyncs=%u\n", mode_frames_[0],
                  mode_frames_[1], mode_frames_[2], mode_frames_[3], resyncs_);
  }

  const ClientOptions& o_;
  std::unique_ptr<Viewer> viewer_;  // --window
  SceneGl g_;
  std::unique_ptr<BoxOverlay> overlay_;  // --window, O; after g_: its GL objects go before the context
  std::vector<Camera> path_;
  wire::Hello mine_;
  NodeLink nodes_[2];
  std::vector<std::unique_ptr<net::Connection>> dropped_;
  DiffReceiver streams_[2];
  bool switch_ = false;       // two switch nodes (not one occlusion_server)
  bool need_resync_ = false;  // the nodes that are up start over at the next frame
  uint32_t epoch_ = 0, resyncs_ = 0, next_camera_ = 0;
  std::optional<uint32_t> resync_frame_;  // the frame of the last resync
  std::optional<uint32_t> prev_camera_;   // the camera of the previous frame (cameras strictly increase)
  size_t mode_frames_[4] = {0, 0, 0, 0};
  // The rejoiner thread (rejoin_loop) and what it shares with the renderer thread.
  std::thread rejoiner_;
  std::atomic<bool> stop_rejoin_{false};
  std::mutex rejoin_mu_;
  bool wanted_[2] = {false, false};
  std::unique_ptr<net::Connection> rejoined_[2];
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
  OcclusionGate gate_;                // occlusion only where it pays (--occlusion-gate)
  // Frustum sets culled here (--two-pass): on = two passes, off = one; measured by render time.
  // Its first frame draws everything in pass 1 (nothing showed before): the trial waits for 3.
  OcclusionGate two_pass_gate_;
  std::unique_ptr<TwoPassDrawer> two_pass_;
  bool two_pass_last_ = false, switch_culled_last_ = false;
  std::vector<uint32_t> last_visible_;  // the last visible set the switch culled with occlusion
  uint32_t two_pass_frames_ = 0, two_pass_used_ = 0, two_pass_redrawn_ = 0;
  std::vector<uint8_t> cam_occlusion_;  // per camera sent: Camera.occlusion (0 frustum set, 1, 2 selected occluders)
};

}  // namespace

int run_cluster_client(const ClientOptions& o) { return Client(o).run(); }

}  // namespace occ
