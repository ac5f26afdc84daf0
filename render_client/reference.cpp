// Single-process renderers on the same path and viewport as the cluster: the reference (no
// culling or hierarchical frustum culling: the ground truth every cluster frame is compared
// with) and the single-process occlusion baselines (stop-and-wait, CHC). With --exact, an item
// buffer pass per frame counts the exactly visible nodes (paper Tables 2 and 3).
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <iostream>
#include <iterator>

#include "common/camera_path.hpp"
#include "common/cpu_time.hpp"
#include "common/culling.hpp"
#include "common/gl/box_query.hpp"
#include "common/gl/context.hpp"
#include "common/gl/startup.hpp"
#include "common/gl/scene_renderer.hpp"
#include "common/memory.hpp"
#include "common/progress.hpp"
#include "render_client/baselines/single_process.hpp"
#include "render_client/frame_output.hpp"
#include "render_client/options.hpp"
#include "render_client/scene_export.hpp"
#include "render_client/viewer.hpp"

namespace occ {

int run_reference(const ClientOptions& o) {
  const Viewport vp{o.width, o.height};
  std::vector<Camera> path;
  std::unique_ptr<Viewer> viewer;  // --window: path grows with next_camera()
  if (o.window) viewer = std::make_unique<Viewer>(o);
  SceneGl g = start_scene_gl("render_client", o.scene, false, o.gl, o.width, o.height, [&](const LoadedScene& ls) {
    if (viewer)
      viewer->start(ls.scene.bounds(), vp);
    else
      path = load_camera_path(o.path, ls.scene.bounds(), vp);
    if (!o.save_path.empty()) save_camera_path(o.save_path, path);
    if (!o.save_scene.empty()) save_gltf(ls.scene, o.save_scene);
  });
  const Hierarchy& h = g.hierarchy();
  GlContext* ctx = g.ctx.get();
  SceneRenderer& renderer = *g.renderer;
  // One process with the machine to itself: parts sized to the frame keep llvmpipe's rasteriser
  // thread busy while the rest is binned (the cluster's processes keep fixed parts: set_flush_automatic).
  renderer.set_flush_automatic();
  BoxQuerier querier(*ctx);
  ChcRenderer chc(h);
  // cpu_ms: CPU time of the whole process (llvmpipe's threads included) for the frame's rendering.
  std::vector<std::string> columns{"frame", "nodes_drawn", "triangles_drawn", "render_ms", "queries", "cpu_ms"};
  // exact_visible/exact_triangles: the nodes seen in an item buffer of every leaf in the frustum;
  // missed_visible: how many of them this method did not draw (0 for a conservative method);
  // exact_added/exact_removed: how the exact set changed from the frame before (its own id churn:
  // what an incremental visible set could save at best on this path, scripts/spikes_report.py);
  // oracle_ms/oracle_cpu_ms: a shaded render of exactly the visible nodes, what a renderer that
  // knew visibility for free would pay (the scene's own frame-to-frame variation, issue 15);
  // oracle_diff_pixels: where that render differs from the frame (0 unless the item buffer missed
  // a visible node; -1 with --no-images: not compared).
  if (o.exact)
    columns.insert(columns.end(), {"exact_visible", "exact_triangles", "missed_visible", "exact_added", "exact_removed",
                                   "oracle_ms", "oracle_cpu_ms", "oracle_diff_pixels"});
  FrameOutput out(o.out, !o.no_images, columns);

  std::vector<uint32_t> all_leaves;
  for (uint32_t id = 0; id < h.size(); ++id)
    if (h.node(id).leaf() && h.node(id).item_count > 0) all_leaves.push_back(id);

  // BLEND items (glass) are not in the item buffer: each one whose leaf the item buffer did not
  // show is counted by an occlusion query against the item buffer's depth (query_blended_items).
  std::vector<uint32_t> blended_items, blended_leaf, blended_queries;
  if (o.exact && renderer.has_blended()) {
    for (uint32_t leaf : all_leaves)
      for (uint32_t i = h.node(leaf).first_item; i < h.node(leaf).first_item + h.node(leaf).item_count; ++i)
        if (renderer.item_blended(i)) {
          blended_items.push_back(i);
          blended_leaf.push_back(leaf);
        }
    blended_queries.resize(blended_items.size());
    if (!blended_queries.empty())
      ctx->gl().CreateQueries(GL_SAMPLES_PASSED, GLsizei(blended_queries.size()), blended_queries.data());
  }

  std::vector<uint32_t> prev_seen;  // --exact: the exact set of the frame before
  double total_ms = 0;
  uint64_t total_tris = 0;
  std::vector<double> frame_ms;
  for (uint32_t f = 0; f < path.size() || (viewer && viewer->next_camera(path)); ++f) {
    const Camera& cam = path[f];
    auto t0 = std::chrono::steady_clock::now();
    const uint64_t cpu0 = process_cpu_us();
    // The baselines draw a leaf at a time, front to back: their BLEND items wait for end_frame().
    const bool baseline = o.cull != "none" && o.cull != "frustum";
    renderer.begin_frame(cam, true, baseline);
    BaselineStats st;
    if (o.cull == "none" || o.cull == "frustum") {
      std::vector<uint32_t> nodes = o.cull == "none" ? all_leaves : frustum_cull(h, cam);
      DrawStats d = renderer.draw_items(items_of_nodes(h, nodes), SceneRenderer::Mode::Shaded);
      st.nodes_drawn = nodes.size();
      st.triangles = d.triangles;
      if (o.exact) st.drawn = std::move(nodes);
    } else if (o.cull == "stop-and-wait") {
      st = render_stop_and_wait(h, cam, renderer, querier);
    } else {
      st = chc.render(cam, renderer, querier);
    }
    st.triangles += renderer.end_frame().triangles;
    ctx->gl().Finish();
    const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    const double cpu_ms = double(process_cpu_us() - cpu0) / 1000.0;
    Image image;
    if (out.writes_images() || viewer) image = ctx->read_rgba();
    if (out.writes_images()) out.write_frame(f, image);
    if (viewer) viewer->show(cam, std::move(image), {ms, st.nodes_drawn, all_leaves.size(), st.triangles, 0.0, -1, ""});
    std::vector<double> row{double(f), double(st.nodes_drawn), double(st.triangles), ms, double(st.queries), cpu_ms};
    if (o.exact) {
      renderer.begin_id_frame(cam);
      // Leaves outside the frustum are clipped whole (no depth clamp): the frustum's leaves give
      // the same image as all leaves, at a fraction of the cost on large scenes.
      renderer.draw_nodes_ids(frustum_cull(h, cam));
      std::vector<uint32_t> seen = ids_in_image(ctx->read_rgba());
      if (!blended_items.empty()) {
        renderer.query_blended_items(blended_items, blended_queries);
        for (size_t k = 0; k < blended_items.size(); ++k) {
          GLuint64 samples = 0;
          ctx->gl().GetQueryObjectui64v(blended_queries[k], GL_QUERY_RESULT, &samples);
          if (samples > 0) seen.push_back(blended_leaf[k]);
        }
        std::sort(seen.begin(), seen.end());
        seen.erase(std::unique(seen.begin(), seen.end()), seen.end());
      }
      uint64_t tris = 0;
      for (uint32_t id : seen) tris += h.node(id).triangles;  // ids_in_image gives node ids
      std::sort(st.drawn.begin(), st.drawn.end());
      size_t missed = 0;
      for (uint32_t id : seen) missed += !std::binary_search(st.drawn.begin(), st.drawn.end(), id);
      std::vector<uint32_t> changed;
      std::set_difference(seen.begin(), seen.end(), prev_seen.begin(), prev_seen.end(), std::back_inserter(changed));
      const size_t added = changed.size();
      changed.clear();
      std::set_difference(prev_seen.begin(), prev_seen.end(), seen.begin(), seen.end(), std::back_inserter(changed));
      const auto o0 = std::chrono::steady_clock::now();
      const uint64_t ocpu0 = process_cpu_us();
      renderer.begin_frame(cam, true);
      renderer.draw_items(items_of_nodes(h, seen), SceneRenderer::Mode::Shaded);
      renderer.end_frame();
      ctx->gl().Finish();
      const double oracle_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - o0).count();
      const double oracle_cpu_ms = double(process_cpu_us() - ocpu0) / 1000.0;
      double diff_pixels = -1;
      if (!image.rgba.empty()) {
        const Image oracle = ctx->read_rgba();
        diff_pixels = 0;
        for (size_t p = 0; p + 3 < image.rgba.size() && p + 3 < oracle.rgba.size(); p += 4)
          diff_pixels += !std::equal(&image.rgba[p], &image.rgba[p] + 4, &oracle.rgba[p]);
      }
      row.insert(row.end(), {double(seen.size()), double(tris), double(missed), double(added), double(changed.size()),
                             oracle_ms, oracle_cpu_ms, diff_pixels});
      prev_seen = std::move(seen);
    }
    out.write_row(row);
    total_ms += ms;
    total_tris += st.triangles;
    frame_ms.push_back(ms);
    if (viewer && viewer->quit()) break;
    if (f % 10 == 9 || f + 1 == path.size()) progress("render_client: frame %u/%zu", f + 1, path.size());
  }
  progress_done();
  if (viewer) viewer->finish();  // writes --record
  if (frame_ms.empty()) return 0;  // --window: the user quit before the first frame
  std::sort(frame_ms.begin(), frame_ms.end());
  std::printf("reference (%s): frames=%zu mean_ms=%.2f median_ms=%.2f mean_fps=%.2f triangles_per_frame=%.0f "
              "mtri_per_s=%.2f peak_rss_mb=%ld\n",
              o.cull.c_str(), frame_ms.size(), total_ms / frame_ms.size(), frame_ms[frame_ms.size() / 2],
              1000.0 * frame_ms.size() / total_ms, double(total_tris) / frame_ms.size(), total_tris / total_ms / 1000.0,
              peak_rss_mb());
  return 0;
}

}  // namespace occ
