#include "render_client/client_stats.hpp"

#include <algorithm>
#include <cstdio>
#include <numeric>
#include <type_traits>

#include "common/memory.hpp"
#include "render_client/run_table.hpp"

namespace occ {

namespace {

double ms_between(RunStats::Clock::time_point a, RunStats::Clock::time_point b) {
  return std::chrono::duration<double, std::milli>(b - a).count();
}

}  // namespace

const char* mode_name(Mode m) {
  switch (m) {
    case Mode::switch_: return "switch";
    case Mode::resync: return "resync";
    case Mode::single: return "single";
    case Mode::frustum: return "frustum";
  }
  return "?";
}

std::vector<std::string> FrameStats::columns() {
  std::vector<std::string> names;
  FrameStats{}.fields([&](const char* name, const auto&) { names.emplace_back(name); });
  return names;
}

void FrameStats::write(FrameOutput& out) const {
  std::vector<double> numbers;
  std::vector<std::string> text;  // FrameOutput: the text columns come last
  fields([&](const char*, const auto& v) {
    if constexpr (std::is_arithmetic_v<std::decay_t<decltype(v)>>)
      numbers.push_back(double(v));
    else
      text.push_back(v);
  });
  out.write_row(numbers, text);
}

void RunStats::start(Clock::time_point t, uint64_t cpu_us) {
  start_ = t;
  last_cpu_us_ = cpu_us;
}

double RunStats::interval_ms(Clock::time_point shown) const {
  return ms_between(shown_.empty() ? start_ : shown_.back(), shown);
}

void RunStats::add(const FrameStats& row, Clock::time_point shown, uint64_t cpu_shown_us) {
  shown_.push_back(shown);
  last_cpu_us_ = cpu_shown_us;
  latency_.push_back(row.latency_ms);
  visible_ += row.visible;
  bytes_ += row.bytes_received;
  full_set_bytes_ += row.full_set_bytes;
  triangles_ += row.triangles;
  hc_ms_ += row.hc_ms;
  or_ms_ += row.or_ms;
  rvg_ms_ += row.rvg_ms;
  wait_ms_ += row.wait_ms;
  camera_gap_max_ = std::max(camera_gap_max_, row.camera_gap);
  ++mode_frames_[int(row.mode)];
  rvg_ms_each_.push_back(row.rvg_ms);
  wait_ms_each_.push_back(row.wait_ms);
  without_occlusion_ += row.hc_node >= 0 && row.occlusion == 0;
  if (row.hc_node == 0 || row.hc_node == 1) {
    node_or_ms_[row.hc_node].push_back(row.or_ms);
    node_hc_ms_[row.hc_node].push_back(row.hc_ms);
  }
}

std::vector<double> RunStats::intervals_ms() const {
  std::vector<double> intervals;
  Clock::time_point prev = start_;
  for (auto t : shown_) {
    intervals.push_back(ms_between(prev, t));
    prev = t;
  }
  return intervals;
}

void RunStats::print_table(size_t leaves, uint64_t scene_triangles, const std::string (&backends)[2]) const {
  const size_t frames = shown_.size();
  if (frames == 0) return;
  std::string title = format("run (%zu frames", frames);
  if (!all_switch()) {
    const char* sep = ": ";
    for (Mode m : {Mode::switch_, Mode::resync, Mode::single, Mode::frustum}) {
      if (mode_frames_[int(m)] == 0) continue;
      title += format("%s%zu %s", sep, mode_frames_[int(m)], mode_name(m));
      sep = ", ";
    }
  }
  if (without_occlusion_ > 0) title += format("; %zu served without occlusion", without_occlusion_);
  RunTable t(title + ")");
  t.times("frame ms", intervals_ms());
  t.times("render client draw ms", rvg_ms_each_);
  t.times("render client wait ms", wait_ms_each_);
  for (int k = 0; k < 2; ++k) {
    if (backends[k].empty() && node_or_ms_[k].empty()) continue;  // no such node
    t.times(format("node %d OR ms", k), node_or_ms_[k]);
    t.times(format("node %d HC ms", k), node_hc_ms_[k]);
  }
  t.text("fps", format("%.2f", 1000.0 * frames / ms_between(start_, shown_.back())));
  t.text("culled (not drawn)",
         format("%.1f %% of objects, %.1f %% of triangles", 100.0 * (1.0 - double(visible_) / frames / std::max<size_t>(leaves, 1)),
                100.0 * (1.0 - double(triangles_) / frames / std::max<uint64_t>(scene_triangles, 1))));
  t.text("wrong pixels", "not checked (frame_diff compares frames with a reference run's)");
  t.text("bytes a frame", format("%.0f B received from the nodes (mean; the whole visible sets would take %.0f B)",
                                 double(bytes_) / frames, double(full_set_bytes_) / frames));
  std::string names;
  for (int k = 0; k < 2; ++k)
    if (!backends[k].empty()) names += format("%snode %d %s", names.empty() ? "" : ", ", k, backends[k].c_str());
  t.text("occlusion back end", names.empty() ? "none (frustum culling here)" : names);
  t.print(stdout);
}

void RunStats::print(size_t leaves, uint64_t scene_triangles, uint32_t resyncs,
                     uint32_t frames_without_occlusion) const {
  const size_t frames = shown_.size();
  if (frames == 0) return;
  std::vector<double> intervals = intervals_ms();
  std::vector<double> lat = latency_;
  std::sort(intervals.begin(), intervals.end());
  std::sort(lat.begin(), lat.end());
  const double wall_ms = ms_between(start_, shown_.back());
  const double mean_v = double(visible_) / frames;
  const double latency_sum = std::accumulate(lat.begin(), lat.end(), 0.0);
  std::printf(
      "summary: frames=%zu mean_fps=%.2f median_fps=%.2f mean_bytes_per_frame=%.0f mean_visible=%.1f "
      "leaves=%zu culled_pct=%.1f mean_triangles=%.0f triangles_culled_pct=%.1f latency_ms_mean=%.1f "
      "latency_ms_p95=%.1f hc_ms_mean=%.2f or_ms_mean=%.2f rvg_ms_mean=%.2f wait_ms_mean=%.2f peak_rss_mb=%ld "
      "latency_frames=%.2f camera_gap_max=%u frames_without_occlusion=%u frame_ms_median=%.2f frame_ms_p99=%.2f\n",
      frames, 1000.0 * frames / wall_ms, 1000.0 / intervals[frames / 2], double(bytes_) / frames, mean_v, leaves,
      100.0 * (1.0 - mean_v / std::max<size_t>(leaves, 1)), double(triangles_) / frames,
      100.0 * (1.0 - double(triangles_) / frames / std::max<uint64_t>(scene_triangles, 1)), latency_sum / frames,
      lat[std::min(frames - 1, frames * 95 / 100)], hc_ms_ / frames, or_ms_ / frames, rvg_ms_ / frames,
      wait_ms_ / frames, peak_rss_mb(), latency_sum / wall_ms, camera_gap_max_, frames_without_occlusion,
      spread(intervals).median, spread(intervals).p99);
  if (!all_switch())
    std::printf("modes: switch=%zu resync=%zu single=%zu frustum=%zu resyncs=%u\n", mode_frames_[0], mode_frames_[1],
                mode_frames_[2], mode_frames_[3], resyncs);
  std::fflush(stdout);  // before what the client writes to stderr next: the table and this line stay one block
}

}  // namespace occ
