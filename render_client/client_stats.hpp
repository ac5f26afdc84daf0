// The render client's statistics: one stats.csv row per frame (FrameStats, docs/output.md has the
// columns) and the run's summary lines (RunStats), both from the same named fields.
#pragma once
#include <chrono>
#include <cstdint>
#include <string>
#include <vector>

#include "render_client/frame_output.hpp"

namespace occ {

// How a frame's visible set was found (stats.csv column `mode`, the window's HUD):
//   switch   the occlusion switch (both nodes), as designed
//   resync   the first frame after a resync (empty sets everywhere: the node's HC sends the full set)
//   single   one switch node serves alone (OR and HC of every frame), the other being down
//   frustum  no node serves: this client's own hierarchical frustum culling
// single and frustum are the degraded modes. Every one is conservative: a frame is drawn from a
// set computed for its own camera, never from a stale one.
enum class Mode { switch_, resync, single, frustum };
const char* mode_name(Mode m);

// One frame's row of a cluster run's stats.csv. fields() is the one list of the columns: it
// names them (the header) and gives their values (the row), in the file's order.
struct FrameStats {
  uint32_t frame = 0, camera = 0;
  int hc_node = -1;  // the node that culled it; -1: frustum culling here
  uint64_t visible = 0, added = 0, removed = 0, queries = 0, triangles = 0, bytes_received = 0;
  // The bytes the frame would have taken with the whole visible set sent instead of the diff.
  uint64_t full_set_bytes = 0;
  double hc_ms = 0, or_ms = 0, rvg_ms = 0, latency_ms = 0, frame_interval_ms = 0;
  double wait_ms = 0;  // waiting for the frame's set from the nodes (0: it was in)
  double hc_cpu_ms = 0, or_cpu_ms = 0, or_tail_cpu_ms = 0, rvg_cpu_ms = 0, rvg_frame_cpu_ms = 0, or_tail_ms = 0;
  uint32_t camera_gap = 0;
  uint32_t occlusion = 0;  // Camera.occlusion of its camera (0: the frustum set)
  uint32_t two_pass = 0;   // 0: one pass; 1 + redrawn: two passes here
  uint64_t hidden_here = 0;
  uint64_t geometry_waits = 0;   // pieces this frame's draw uploaded first (--geometry-budget)
  double geometry_wait_ms = 0;   // and the time that took
  Mode mode = Mode::frustum;

  // f(name, value) for every column; `value` a number, or the mode's name (the last column).
  template <class F>
  void fields(F&& f) const {
    f("frame", frame); f("camera", camera); f("hc_node", hc_node); f("visible", visible); f("added", added);
    f("removed", removed); f("queries", queries); f("triangles", triangles); f("bytes_received", bytes_received);
    f("full_set_bytes", full_set_bytes);
    f("hc_ms", hc_ms); f("or_ms", or_ms); f("rvg_ms", rvg_ms); f("latency_ms", latency_ms);
    f("frame_interval_ms", frame_interval_ms); f("hc_cpu_ms", hc_cpu_ms); f("or_cpu_ms", or_cpu_ms);
    f("or_tail_cpu_ms", or_tail_cpu_ms); f("rvg_cpu_ms", rvg_cpu_ms); f("rvg_frame_cpu_ms", rvg_frame_cpu_ms);
    f("or_tail_ms", or_tail_ms); f("wait_ms", wait_ms); f("camera_gap", camera_gap); f("occlusion", occlusion);
    f("two_pass", two_pass);
    f("hidden_here", hidden_here); f("geometry_waits", geometry_waits); f("geometry_wait_ms", geometry_wait_ms);
    f("mode", std::string(mode_name(mode)));
  }
  static std::vector<std::string> columns();  // the header
  void write(FrameOutput& out) const;         // the row
};

// The run's totals over its rows, for the summary line. The clock starts with start(); each
// frame shown adds its row and the moment it was shown.
class RunStats {
 public:
  using Clock = std::chrono::steady_clock;
  void start(Clock::time_point t, uint64_t cpu_us);
  // Since the previous frame was shown (or the start): wall time (ms) and process CPU time (us).
  double interval_ms(Clock::time_point shown) const;
  uint64_t cpu_since_last_us(uint64_t cpu_shown_us) const { return cpu_shown_us - last_cpu_us_; }
  void add(const FrameStats& row, Clock::time_point shown, uint64_t cpu_shown_us);
  size_t frames() const { return shown_.size(); }
  // Frames other than switch ones: the summary's `modes:` line.
  bool all_switch() const { return mode_frames_[int(Mode::switch_)] == frames(); }
  // The `summary:` line (and `modes:` when not all frames were the switch's): `leaves` and
  // `scene_triangles` of the scene, the resyncs and the gate's frames without occlusion.
  void print(size_t leaves, uint64_t scene_triangles, uint32_t resyncs, uint32_t frames_without_occlusion) const;
  // The table a person reads (run_table.hpp), to print before print()'s line: fps, frame
  // interval, each process's time a frame (the render client's draw and wait; each node's OR and
  // HC over the frames it served, from their EndOfFrame), culled, bytes, and `backends[k]`, the
  // occlusion back end switch node k named in its Hello ("" where none did).
  void print_table(size_t leaves, uint64_t scene_triangles, const std::string (&backends)[2]) const;

 private:
  std::vector<double> intervals_ms() const;  // each frame's frame_interval_ms, in order
  Clock::time_point start_;
  uint64_t last_cpu_us_ = 0;
  std::vector<Clock::time_point> shown_;
  std::vector<double> latency_;
  std::vector<double> rvg_ms_each_, wait_ms_each_;
  std::vector<double> node_or_ms_[2], node_hc_ms_[2];  // over the frames node k served
  size_t without_occlusion_ = 0;  // frames a node served with the frustum set (Camera.occlusion 0)
  uint64_t visible_ = 0, bytes_ = 0, full_set_bytes_ = 0, triangles_ = 0;
  double hc_ms_ = 0, or_ms_ = 0, rvg_ms_ = 0, wait_ms_ = 0;
  uint32_t camera_gap_max_ = 0;
  size_t mode_frames_[4] = {0, 0, 0, 0};
};

}  // namespace occ
