#include "common/gl/startup.hpp"

#include <iostream>

#include "common/camera.hpp"
#include "common/cli.hpp"

namespace occ {

void add_view_options(Cli& cli, SceneOptions& scene, int* width, int* height, GlBackend* backend,
                      const std::string& what) {
  add_scene_options(cli, scene);
  const std::string note = what.empty() ? "" : " (" + what + ")";
  cli.option("width", width, 16, kMaxViewportPx, "viewport width in pixels" + note);
  cli.option("height", height, 16, kMaxViewportPx, "viewport height in pixels" + note);
  cli.choice<GlBackend>("gl", backend,
                        {{"auto", GlBackend::Auto}, {"egl", GlBackend::Egl}, {"osmesa", GlBackend::OSMesa}},
                        "GL back end (auto: EGL, else OSMesa)");
}

std::unique_ptr<GlContext> start_gl(const std::string& who, GlBackend backend, int width, int height) {
  auto ctx = GlContext::create(backend, width, height);
  std::cerr << who << ": GL_RENDERER " << ctx->renderer() << " (" << ctx->backend_name() << ")\n";
  return ctx;
}

SceneGl start_scene_gl(const std::string& who, const SceneOptions& scene, bool with_lod, GlBackend backend,
                       int width, int height, const std::function<void(const LoadedScene&)>& before_gl) {
  SceneGl s;
  s.loaded = std::make_unique<LoadedScene>(load_and_build(scene, who, with_lod));
  if (before_gl) before_gl(*s.loaded);
  const LodData* lod = s.loaded->lod.get();
  s.renderables = std::make_unique<Renderables>(s.loaded->hierarchy, lod);
  s.ctx = start_gl(who, backend, width, height);
  s.renderer = std::make_unique<SceneRenderer>(*s.ctx, s.loaded->scene, s.loaded->hierarchy, lod);
  return s;
}

}  // namespace occ
