// The reference renderer: every leaf (or every leaf in the frustum) drawn shaded, in item order.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <iostream>

#include "common/camera_path.hpp"
#include "common/progress.hpp"
#include "common/culling.hpp"
#include "common/gl/context.hpp"
#include "common/gl/scene_renderer.hpp"
#include "render_client/frame_output.hpp"
#include "render_client/options.hpp"

namespace occ {

int run_reference(const ClientOptions& o) {
  LoadedScene ls = load_and_build(o.scene, "render_client");
  const Hierarchy& h = ls.hierarchy;
  const Viewport vp{o.width, o.height};
  const std::vector<Camera> path = load_camera_path(o.path, ls.scene.bounds(), vp);
  auto ctx = GlContext::create(parse_gl_backend(o.gl), o.width, o.height);
  std::cerr << "render_client: GL_RENDERER " << ctx->renderer() << " (" << ctx->backend_name() << ")\n";
  SceneRenderer renderer(*ctx, ls.scene, h);
  FrameOutput out(o.out, !o.no_images, {"frame", "nodes_drawn", "triangles_drawn", "render_ms"});

  std::vector<uint32_t> all_leaves;
  for (uint32_t id = 0; id < h.size(); ++id)
    if (h.node(id).leaf() && h.node(id).item_count > 0) all_leaves.push_back(id);

  double total_ms = 0;
  uint64_t total_tris = 0;
  std::vector<double> frame_ms;
  for (uint32_t f = 0; f < path.size(); ++f) {
    auto t0 = std::chrono::steady_clock::now();
    std::vector<uint32_t> nodes = o.cull == "none" ? all_leaves : frustum_cull(h, path[f]);
    renderer.begin_frame(path[f], true);
    DrawStats st = renderer.draw_items(items_of_nodes(h, nodes), SceneRenderer::Mode::Shaded);
    ctx->gl().Finish();
    double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    if (out.writes_images()) out.write_frame(f, ctx->read_rgba());
    out.write_row({double(f), double(nodes.size()), double(st.triangles), ms});
    total_ms += ms;
    total_tris += st.triangles;
    frame_ms.push_back(ms);
    if (f % 10 == 9 || f + 1 == path.size())
      progress("render_client: frame %u/%zu", f + 1, path.size());
  }
  std::sort(frame_ms.begin(), frame_ms.end());
  progress_done();
  std::printf("reference (%s): frames=%zu mean_ms=%.2f median_ms=%.2f mean_fps=%.2f triangles_per_frame=%.0f "
              "mtri_per_s=%.2f\n",
              o.cull.c_str(), path.size(), total_ms / path.size(), frame_ms[frame_ms.size() / 2],
              1000.0 * path.size() / total_ms, double(total_tris) / path.size(), total_tris / total_ms / 1000.0);
  return 0;
}

}  // namespace occ
