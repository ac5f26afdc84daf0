// What every GL process does first, written once: the viewport and --gl flags, and the context,
// announced on one line ("switch_node 0: GL_RENDERER llvmpipe (...) (egl-surfaceless)").
// The scene comes from load_and_build() (common/scene_setup.hpp).
#pragma once
#include <memory>
#include <string>

#include "common/gl/context.hpp"

namespace occ {

class Cli;

// --width, --height (16..kMaxViewportPx; `what` says whose viewport, e.g. "must match the render
// client") and --gl auto|egl|osmesa.
void add_view_options(Cli& cli, int* width, int* height, GlBackend* backend, const std::string& what = "");

// Creates the context and prints "<who>: GL_RENDERER <renderer> (<back end>)" to stderr.
std::unique_ptr<GlContext> start_gl(const std::string& who, GlBackend backend, int width, int height);

}  // namespace occ
