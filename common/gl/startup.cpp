#include "common/gl/startup.hpp"

#include <cstdio>
#include <cstdlib>
#include <iostream>

#include "common/camera.hpp"
#include "common/cli.hpp"
#include "common/memory.hpp"
#include "common/progress.hpp"

namespace occ {

void add_view_options(Cli& cli, SceneOptions& scene, int* width, int* height, GlBackend* backend,
                      const std::string& what) {
  add_scene_options(cli, scene);
  const std::string note = what.empty() ? "" : " (" + what + ")";
  cli.option("width", width, 16, kMaxViewportPx, "viewport width in pixels" + note);
  cli.option("height", height, 16, kMaxViewportPx, "viewport height in pixels" + note);
  cli.group(CliGroup::expert);
  cli.choice<GlBackend>("gl", backend,
                        {{"auto", GlBackend::Auto}, {"egl", GlBackend::Egl}, {"osmesa", GlBackend::OSMesa}},
                        "GL back end (auto: EGL on a GPU's device, else Mesa's surfaceless EGL, else OSMesa)");
}

std::unique_ptr<GlContext> start_gl(const std::string& who, GlBackend backend, int width, int height) {
  auto ctx = GlContext::create(backend, width, height);
  std::cerr << who << ": GL_RENDERER " << ctx->renderer() << " (" << ctx->backend_name() << "), GL_VERSION "
            << ctx->version() << ", GL_VENDOR " << ctx->vendor() << ", " << renderer_class_name(ctx->renderer_class())
            << " renderer" << (std::getenv("OCC_RENDERER_CLASS") ? " (OCC_RENDERER_CLASS)" : "") << "\n";
  return ctx;
}

Enclosures find_enclosures(const std::string& who, const Scene& scene, const Hierarchy& h) {
  const double t0 = now_ms();
  Enclosures e = Enclosures::find(scene, h);
  if (e.sealed_items() > 0) {
    char buf[256];
    std::snprintf(buf, sizeof buf, "%s: %u items sealed inside %u closed convex solids (HC skips them; found in %.0f ms)",
                  who.c_str(), e.sealed_items(), e.solids(), now_ms() - t0);
    std::cerr << buf << "\n";
  }
  return e;
}

SceneGl start_scene_gl(const std::string& who, const SceneOptions& scene, bool with_lod, GlBackend backend,
                       int width, int height, const std::function<void(const LoadedScene&)>& before_gl,
                       const std::function<void(const LoadedScene&, const GlContext&)>& before_upload) {
  SceneGl s;
  s.loaded = in_own_arena([&] { return std::make_unique<LoadedScene>(load_and_build(scene, who, with_lod)); });
  if (before_gl) before_gl(*s.loaded);
  LodData* lod = s.loaded->lod.get();
  s.renderables = std::make_unique<Renderables>(s.loaded->hierarchy, lod);
  s.ctx = start_gl(who, backend, width, height);
  if (before_upload) before_upload(*s.loaded, *s.ctx);
  // The driver keeps its own copy of the geometry: the CPU arrays are freed as they are uploaded.
  const double t0 = now_ms();
  s.renderer = std::make_unique<SceneRenderer>(
      *s.ctx, s.loaded->scene, s.loaded->hierarchy, lod,
      SceneRenderer::Upload{.release = true, .budget_bytes = geometry_budget_bytes(scene)});
  char buf[256];
  std::snprintf(buf, sizeof buf, "%s: geometry %s in %.0f ms (RSS %ld MB, peak %ld MB)", who.c_str(),
                s.renderer->geometry_pool() ? "pool ready" : "uploaded, CPU copies released", now_ms() - t0, rss_mb(),
                peak_rss_mb());
  std::cerr << buf << "\n";
  return s;
}

}  // namespace occ
