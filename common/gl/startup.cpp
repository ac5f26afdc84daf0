#include "common/gl/startup.hpp"

#include <iostream>

#include "common/camera.hpp"
#include "common/cli.hpp"

namespace occ {

void add_view_options(Cli& cli, int* width, int* height, GlBackend* backend, const std::string& what) {
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

}  // namespace occ
