// Single-process renderers on the same path and viewport as the cluster: the reference (no
// culling or hierarchical frustum culling: the ground truth every cluster frame is compared
// with) and the single-process occlusion baselines (stop-and-wait, CHC). With --exact, an item
// buffer pass per frame counts the exactly visible nodes (paper Tables 2 and 3).
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <iostream>
#include <iterator>
#include <optional>

#include "common/camera_path.hpp"
#include "common/cpu_time.hpp"
#include "common/cull/culling.hpp"
#include "common/gl/box_query.hpp"
#include "common/gl/context.hpp"
#include "common/gl/startup.hpp"
#include "common/gl/scene_renderer.hpp"
#include "common/memory.hpp"
#include "common/progress.hpp"
#include "render_client/baselines/single_process.hpp"
#include "render_client/frame_output.hpp"
#include "render_client/options.hpp"
#include "render_client/run_table.hpp"
#include "render_client/viewer.hpp"

namespace occ {

const char* cull_name(Cull c) {
  switch (c) {
    case Cull::none: return "none";
    case Cull::frustum: return "frustum";
    case Cull::stop_and_wait: return "stop-and-wait";
    case Cull::chc: return "chc";
  }
  return "?";
}

namespace {

using Clock = std::chrono::steady_clock;

double ms_since(Clock::time_point t0) { return std::chrono::duration<double, std::milli>(Clock::now() - t0).count(); }

// --exact: what the frame's exact visibility says about the method.
//   exact_visible/exact_triangles: the nodes seen in an item buffer of every leaf in the frustum;
//   missed_visible: how many of them this method did not draw (0 for a conservative method);
//   exact_added/exact_removed: how the exact set changed from the frame before (its own id churn:
//     what an incremental visible set could save at best on this path, scripts/spikes_report.py);
//   oracle_ms/oracle_cpu_ms: a shaded render of exactly the visible nodes, what a renderer that
//     knew visibility for free would pay (the scene's own frame-to-frame variation);
//   oracle_diff_pixels: where that render differs from the frame (0 unless the item buffer missed
//     a visible node; -1 with --images off: not compared).
struct ExactStats {
  uint64_t visible = 0, triangles = 0, missed = 0, added = 0, removed = 0;
  double oracle_ms = 0, oracle_cpu_ms = 0, oracle_diff_pixels = -1;
};

// One frame's row of a reference run's stats.csv. fields() is the one list of the columns: it
// names them (the header) and gives their values (the row); the exact columns with --exact.
// cpu_ms: CPU time of the whole process (llvmpipe's threads included) for the frame's rendering.
struct ReferenceRow {
  uint32_t frame = 0;
  uint64_t nodes_drawn = 0, triangles_drawn = 0;
  double render_ms = 0;
  uint64_t queries = 0;
  double cpu_ms = 0;
  std::optional<ExactStats> exact;

  template <class F>
  void fields(bool with_exact, F&& f) const {
    f("frame", frame); f("nodes_drawn", nodes_drawn); f("triangles_drawn", triangles_drawn);
    f("render_ms", render_ms); f("queries", queries); f("cpu_ms", cpu_ms);
    if (!with_exact) return;
    const ExactStats e = exact.value_or(ExactStats{});
    f("exact_visible", e.visible); f("exact_triangles", e.triangles); f("missed_visible", e.missed);
    f("exact_added", e.added); f("exact_removed", e.removed); f("oracle_ms", e.oracle_ms);
    f("oracle_cpu_ms", e.oracle_cpu_ms); f("oracle_diff_pixels", e.oracle_diff_pixels);
  }
  static std::vector<std::string> columns(bool with_exact) {
    std::vector<std::string> names;
    ReferenceRow{}.fields(with_exact, [&](const char* name, auto) { names.emplace_back(name); });
    return names;
  }
  std::vector<double> values() const {
    std::vector<double> v;
    fields(exact.has_value(), [&](const char*, auto x) { v.push_back(double(x)); });
    return v;
  }
};

// --exact: the exactly visible nodes of each frame (an item buffer of the frustum's leaves, and
// an occlusion query per BLEND item, which the item buffer does not hold), and an oracle render
// of just them.
class ExactVisibility {
 public:
  ExactVisibility(const Hierarchy& h, GlContext& ctx, SceneRenderer& renderer, const std::vector<uint32_t>& leaves)
      : h_(h), ctx_(ctx), renderer_(renderer) {
    if (!renderer.has_blended()) return;
    for (uint32_t leaf : leaves)
      for (uint32_t i = h.node(leaf).first_item; i < h.node(leaf).first_item + h.node(leaf).item_count; ++i)
        if (renderer.item_blended(i)) {
          blended_items_.push_back(i);
          blended_leaf_.push_back(leaf);
        }
    blended_queries_.resize(blended_items_.size());
    if (!blended_queries_.empty())
      ctx.gl().CreateQueries(GL_SAMPLES_PASSED, GLsizei(blended_queries_.size()), blended_queries_.data());
  }

  // The frame just drawn with `cam` (`image`: it, or empty with --images off) by a method that
  // drew the leaves `drawn`.
  ExactStats measure(const Camera& cam, std::vector<uint32_t> drawn, const Image& image) {
    ExactStats e;
    std::vector<uint32_t> seen = seen_nodes(cam);
    for (uint32_t id : seen) e.triangles += h_.node(id).triangles;  // ids_in_image gives node ids
    std::sort(drawn.begin(), drawn.end());
    for (uint32_t id : seen) e.missed += !std::binary_search(drawn.begin(), drawn.end(), id);
    std::vector<uint32_t> changed;
    std::set_difference(seen.begin(), seen.end(), prev_seen_.begin(), prev_seen_.end(), std::back_inserter(changed));
    e.added = changed.size();
    changed.clear();
    std::set_difference(prev_seen_.begin(), prev_seen_.end(), seen.begin(), seen.end(), std::back_inserter(changed));
    e.removed = changed.size();
    e.visible = seen.size();
    oracle(cam, seen, image, e);
    prev_seen_ = std::move(seen);
    return e;
  }

 private:
  // The nodes seen with `cam`, sorted. Leaves outside the frustum are clipped whole (no depth
  // clamp): the frustum's leaves give the same image as all leaves, at a fraction of the cost on
  // large scenes.
  std::vector<uint32_t> seen_nodes(const Camera& cam) {
    renderer_.begin_id_frame(cam);
    renderer_.draw_nodes_ids(frustum_cull(h_, cam));
    std::vector<uint32_t> seen = ids_in_image(ctx_.read_rgba());
    if (blended_items_.empty()) return seen;
    renderer_.query_blended_items(blended_items_, blended_queries_);
    for (size_t k = 0; k < blended_items_.size(); ++k) {
      GLuint64 samples = 0;
      ctx_.gl().GetQueryObjectui64v(blended_queries_[k], GL_QUERY_RESULT, &samples);
      if (samples > 0) seen.push_back(blended_leaf_[k]);
    }
    std::sort(seen.begin(), seen.end());
    seen.erase(std::unique(seen.begin(), seen.end()), seen.end());
    return seen;
  }

  // A shaded render of just `seen`: its cost, and the pixels where it differs from `image`.
  void oracle(const Camera& cam, const std::vector<uint32_t>& seen, const Image& image, ExactStats& e) {
    const Clock::time_point t0 = Clock::now();
    const uint64_t cpu0 = process_cpu_us();
    renderer_.begin_frame(cam, true);
    renderer_.draw_items(items_of_nodes(h_, seen), SceneRenderer::Mode::Shaded);
    renderer_.end_frame();
    ctx_.gl().Finish();
    e.oracle_ms = ms_since(t0);
    e.oracle_cpu_ms = double(process_cpu_us() - cpu0) / 1000.0;
    if (image.rgba.empty()) return;
    const Image oracle = ctx_.read_rgba();
    e.oracle_diff_pixels = 0;
    for (size_t p = 0; p + 3 < image.rgba.size() && p + 3 < oracle.rgba.size(); p += 4)
      e.oracle_diff_pixels += !std::equal(&image.rgba[p], &image.rgba[p] + 4, &oracle.rgba[p]);
  }

  const Hierarchy& h_;
  GlContext& ctx_;
  SceneRenderer& renderer_;
  std::vector<uint32_t> blended_items_, blended_leaf_, blended_queries_;
  std::vector<uint32_t> prev_seen_;  // the exact set of the frame before
};

class ReferenceRun {
 public:
  explicit ReferenceRun(const ClientOptions& o) : o_(o) {}

  int run() {
    start();
    for (uint32_t f = 0; f < path_.size() || (viewer_ && viewer_->next_camera(path_)); ++f) {
      frame(f, path_[f]);
      if (viewer_ && viewer_->quit()) break;
      if (f % 10 == 9 || f + 1 == path_.size()) progress("render_client: frame %u/%zu", f + 1, path_.size());
    }
    progress_done();
    if (viewer_) viewer_->finish();  // writes OUT/path.csv
    summary();
    return 0;
  }

 private:
  // The scene, GL and the camera path (or the viewer); the baselines' queriers, the leaves.
  void start() {
    const Viewport vp{o_.width, o_.height};
    if (o_.viewer()) viewer_ = std::make_unique<Viewer>(o_);  // path_ grows with next_camera()
    g_ = start_scene_gl("render_client", o_.scene, false, o_.gl, o_.width, o_.height, [&](const LoadedScene& ls) {
      if (viewer_)
        viewer_->start(ls.scene.bounds(), vp);
      else
        path_ = load_camera_path(o_.path, ls.scene.bounds(), vp);
      if (!o_.record.empty() && !viewer_) save_camera_path(o_.record, path_);
    });
    // One process with the machine to itself: parts sized to the frame keep llvmpipe's rasteriser
    // thread busy while the rest is binned (the cluster's processes keep fixed parts: set_flush_automatic).
    g_.renderer->set_flush_automatic();
    querier_.emplace(*g_.ctx);
    chc_.emplace(g_.hierarchy());
    out_.emplace(o_.out, !o_.no_images, ReferenceRow::columns(o_.exact));
    if (o_.item_buffer) out_->write_item_space(g_.hierarchy());
    const Hierarchy& h = g_.hierarchy();
    for (uint32_t id = 0; id < h.size(); ++id)
      if (h.node(id).leaf() && h.node(id).item_count > 0) all_leaves_.push_back(id);
    // BLEND items (glass) are not in the item buffer: each one whose leaf the item buffer did not
    // show is counted by an occlusion query against the item buffer's depth (query_blended_items).
    if (o_.exact) exact_.emplace(h, *g_.ctx, *g_.renderer, all_leaves_);
  }

  // Frame f with the method of --cull, finished.
  BaselineStats draw(const Camera& cam) {
    const Hierarchy& h = g_.hierarchy();
    SceneRenderer& renderer = *g_.renderer;
    // The baselines draw a leaf at a time, front to back: their BLEND items wait for end_frame().
    const bool baseline = o_.cull == Cull::stop_and_wait || o_.cull == Cull::chc;
    renderer.begin_frame(cam, true, baseline);
    BaselineStats st;
    if (!baseline) {
      std::vector<uint32_t> nodes = o_.cull == Cull::none ? all_leaves_ : frustum_cull(h, cam);
      DrawStats d = renderer.draw_items(items_of_nodes(h, nodes), SceneRenderer::Mode::Shaded);
      st.nodes_drawn = nodes.size();
      st.triangles = d.triangles;
      if (o_.exact) st.drawn = std::move(nodes);
    } else if (o_.cull == Cull::stop_and_wait) {
      st = render_stop_and_wait(h, cam, renderer, *querier_);
    } else {
      st = chc_->render(cam, renderer, *querier_);
    }
    st.triangles += renderer.end_frame().triangles;
    g_.ctx->gl().Finish();
    return st;
  }

  // Frame f: drawn, shown, measured, written.
  void frame(uint32_t f, const Camera& cam) {
    const Clock::time_point t0 = Clock::now();
    const uint64_t cpu0 = process_cpu_us();
    BaselineStats st = draw(cam);
    ReferenceRow row{f, st.nodes_drawn, st.triangles, ms_since(t0), st.queries, double(process_cpu_us() - cpu0) / 1000.0, std::nullopt};
    Image image;
    if (out_->writes_images() || viewer_) image = g_.ctx->read_rgba();
    if (out_->writes_images()) out_->write_frame(f, image);
    if (viewer_)
      viewer_->show(cam, std::move(image), {row.render_ms, st.nodes_drawn, all_leaves_.size(), st.triangles, 0.0, -1, "", f});
    if (exact_) row.exact = exact_->measure(cam, std::move(st.drawn), image);
    if (o_.item_buffer) {  // full detail: every item in the frustum, in colour item index + 1
      g_.renderer->begin_id_frame(cam);
      g_.renderer->draw_items(items_of_nodes(g_.hierarchy(), frustum_cull(g_.hierarchy(), cam)), SceneRenderer::Mode::ItemIds);
      out_->write_items(f, g_.ctx->read_rgba(), g_.ctx->read_depth());
    }
    out_->write_row(row.values());
    total_ms_ += row.render_ms;
    total_tris_ += st.triangles;
    total_nodes_ += st.nodes_drawn;
    if (row.exact) total_missed_ += row.exact->missed;
    frame_ms_.push_back(row.render_ms);
  }

  // The table a person reads (run_table.hpp), as the cluster's has it where it applies: one
  // process, no bytes; the frame time is the draw's.
  void print_table() const {
    const size_t n = frame_ms_.size();
    const bool queries = o_.cull == Cull::stop_and_wait || o_.cull == Cull::chc;
    RunTable t(format("run (%zu frames, one process: --cull %s)", n, cull_name(o_.cull)));
    t.times("frame ms (draw)", frame_ms_);
    t.text("fps", format("%.2f", 1000.0 * n / total_ms_));
    t.text("culled (not drawn)",
           format("%.1f %% of objects, %.1f %% of triangles",
                  100.0 * (1.0 - double(total_nodes_) / n / std::max<size_t>(all_leaves_.size(), 1)),
                  100.0 * (1.0 - double(total_tris_) / n / std::max<uint64_t>(g_.scene().triangle_count(), 1))));
    std::string wrong = queries ? "not checked (frame_diff compares frames with a --cull frustum run's)"
                                : "none by definition (the reference; frame_diff compares other runs with it)";
    if (o_.exact) wrong += format("; --exact: %llu visible objects not drawn", (unsigned long long)total_missed_);
    t.text("wrong pixels", wrong);
    t.text("occlusion back end", queries ? "queries (GL occlusion queries)" : "none (no occlusion culling)");
    t.print(stdout);
  }

  void summary() {
    if (frame_ms_.empty()) return;  // --window: the user quit before the first frame
    print_table();
    std::sort(frame_ms_.begin(), frame_ms_.end());
    const size_t n = frame_ms_.size();
    std::printf("reference (%s): frames=%zu mean_ms=%.2f median_ms=%.2f mean_fps=%.2f triangles_per_frame=%.0f "
                "mtri_per_s=%.2f peak_rss_mb=%ld\n",
                cull_name(o_.cull), n, total_ms_ / n, frame_ms_[n / 2], 1000.0 * n / total_ms_,
                double(total_tris_) / n, total_tris_ / total_ms_ / 1000.0, peak_rss_mb());
    print_geometry_line(stdout, "reference", g_.renderer->geometry_pool());
  }

  const ClientOptions& o_;
  std::vector<Camera> path_;
  std::unique_ptr<Viewer> viewer_;  // --window, --web
  SceneGl g_;
  std::optional<BoxQuerier> querier_;
  std::optional<ChcRenderer> chc_;
  std::optional<FrameOutput> out_;
  std::optional<ExactVisibility> exact_;  // --exact
  std::vector<uint32_t> all_leaves_;
  double total_ms_ = 0;
  uint64_t total_tris_ = 0, total_nodes_ = 0, total_missed_ = 0;
  std::vector<double> frame_ms_;
};

}  // namespace

int run_reference(const ClientOptions& o) { return ReferenceRun(o).run(); }

}  // namespace occ
