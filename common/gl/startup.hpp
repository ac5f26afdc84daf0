// What every GL process does first, written once: the scene, viewport and --gl flags, then the
// scene (load_and_build), its renderables and a context with a renderer, announced on one line
// each ("switch_node 0: GL_RENDERER llvmpipe (...) (egl-surfaceless), GL_VERSION 4.5 (Core Profile)
// Mesa 22.3.6, GL_VENDOR Mesa, software renderer").
#pragma once
#include <functional>
#include <memory>
#include <string>

#include "common/cull/depth_raster.hpp"
#include "common/cull/enclosure.hpp"
#include "common/gl/context.hpp"
#include "common/gl/scene_renderer.hpp"
#include "common/setup/scene_setup.hpp"

namespace occ {

class Cli;

// --scene and the hierarchy flags, --width, --height (16..kMaxViewportPx; `what` says whose
// viewport, e.g. "must match the render client") and --gl auto|egl|osmesa.
void add_view_options(Cli& cli, SceneOptions& scene, int* width, int* height, GlBackend* backend,
                      const std::string& what = "");

// Creates the context and prints "<who>: GL_RENDERER <renderer> (<back end>), GL_VERSION <version>,
// GL_VENDOR <vendor>, <software|hardware> renderer" to stderr: which GPU and driver, and the
// renderer class (GlContext::renderer_class(); the defaults that differ by it: docs/gpu.md).
std::unique_ptr<GlContext> start_gl(const std::string& who, GlBackend backend, int width, int height);

// Enclosures::find, with one line on stderr when some item is sealed ("<who>: N items sealed inside
// M closed convex solids ...").
Enclosures find_enclosures(const std::string& who, const Scene& scene, const Hierarchy& h);

// A process's scene and GL state. The members refer to each other: keep the object in place.
struct SceneGl {
  std::unique_ptr<LoadedScene> loaded;
  std::unique_ptr<Renderables> renderables;  // with the LOD data when loaded with LODs
  Enclosures sealed;                         // items sealed inside solids (the switch nodes fill it before the upload)
  std::unique_ptr<CpuOccluders> cpu_occluders;  // the switch nodes' OR on the CPU (--backend cpu), else null
  std::unique_ptr<GlContext> ctx;
  std::unique_ptr<SceneRenderer> renderer;
  const Scene& scene() const { return loaded->scene; }
  const Hierarchy& hierarchy() const { return loaded->hierarchy; }
  uint64_t fingerprint() const { return loaded->fingerprint; }
};

// load_and_build(scene, who, with_lod), then `before_gl` (e.g. check the camera path against
// the scene before paying for a context), then start_gl(), `before_upload` (what needs the
// geometry on the CPU and the renderer: find_enclosures, a CPU copy for a software renderer) and
// a SceneRenderer (with the LODs), which releases the CPU geometry.
SceneGl start_scene_gl(const std::string& who, const SceneOptions& scene, bool with_lod, GlBackend backend,
                       int width, int height, const std::function<void(const LoadedScene&)>& before_gl = nullptr,
                       const std::function<void(const LoadedScene&, const GlContext&)>& before_upload = nullptr);

}  // namespace occ
