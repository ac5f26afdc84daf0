// A headless OpenGL 4.5 core context with its own offscreen framebuffer (no window system).
// Back ends: EGL (the EGL device platform on a hardware GPU, else Mesa's surfaceless platform,
// else a software device: llvmpipe) and OSMesa as a fallback, loaded at run time (dlopen) so the
// binaries start with only EGL present. The framebuffer object is RGBA8 colour plus
// GL_DEPTH_COMPONENT32F depth (a texture) and stays bound; reverse-Z is set up once for occ::Camera's
// projection: glClipControl(GL_LOWER_LEFT, GL_ZERO_TO_ONE), depth test GL_GREATER, depth cleared
// to 0 (= far). Depth clamp stays off: clamping would rasterise geometry in front of the near
// plane at depth 1 instead of clipping it, and occlusion boxes crossing the near plane are
// decided on the CPU anyway (visible_without_query in common/cull/culling.hpp).
// One context per thread at a time; the library prints nothing (callers print renderer()).
#pragma once
#include <memory>
#include <string>
#include <vector>

#include "common/gl/gl_api.hpp"
#include "common/gl/renderer_class.hpp"
#include "common/image.hpp"

namespace occ {

enum class GlBackend { Auto, Egl, OSMesa };

// "auto" | "egl" | "osmesa"; throws InputError("--gl 'x': expected egl, osmesa or auto").
GlBackend parse_gl_backend(const std::string& name);

namespace gl_detail {
class Surface;  // the window-system side of a back end (context_egl.cpp, context_osmesa.cpp)
}

class GlContext {
 public:
  // Creates the context, makes it current on the calling thread and binds a width x height
  // framebuffer. Auto tries EGL (a GPU's device, surfaceless, a software device), then OSMesa. Throws
  // std::runtime_error listing every attempt's reason when none works, InputError for a size
  // outside 1..kMaxViewportPx.
  static std::unique_ptr<GlContext> create(GlBackend backend, int width, int height);
  ~GlContext();
  GlContext(const GlContext&) = delete;
  GlContext& operator=(const GlContext&) = delete;

  const GlApi& gl() const { return gl_; }
  std::string renderer() const;  // GL_RENDERER, e.g. "llvmpipe (LLVM 15.0.6, 256 bits)"
  std::string version() const;   // GL_VERSION
  std::string vendor() const;    // GL_VENDOR
  RendererClass renderer_class() const { return renderer_class_; }  // from GL_RENDERER, GL_VENDOR
  const char* backend_name() const;  // "egl-surfaceless", "egl-device", "osmesa"
  int width() const { return width_; }
  int height() const { return height_; }

  // Makes the context current on the calling thread (and binds its framebuffer and viewport);
  // release_current() on the old thread first: a context is current on one thread at most.
  void make_current();
  void release_current();

  // The colour buffer as RGBA8, top row first (waits for rendering to finish).
  Image read_rgba() const;
  // The depth buffer (reverse-Z: 1 = near, 0 = far), row 0 at the bottom (waits for rendering).
  std::vector<float> read_depth() const;
  void read_depth(float* out) const;  // width() * height() floats
  // Pixels [x, x + w) x [y, y + h) of the depth buffer into a width() x height() array `out`.
  void read_depth(int x, int y, int w, int h, float* out) const;
  // Replaces the depth buffer with `depth` (width() * height() floats, row 0 at the bottom).
  void write_depth(const float* depth);
  // The depth attachment: a GL_DEPTH_COMPONENT32F texture (one level), sampled by compute
  // shaders (texelFetch(...).r is the depth) while it stays attached.
  GLuint depth_texture() const { return depth_tex_; }

 private:
  GlContext(std::unique_ptr<gl_detail::Surface> surface, int width, int height);
  void bind_framebuffer() const;

  std::unique_ptr<gl_detail::Surface> surface_;
  GlApi gl_;
  int width_, height_;
  GLuint fbo_ = 0, color_rb_ = 0, depth_tex_ = 0;
  RendererClass renderer_class_ = RendererClass::hardware;
};

}  // namespace occ
