#include "common/gl/context.hpp"

#include <malloc.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <mutex>
#include <stdexcept>

#include "common/camera.hpp"
#include "common/error.hpp"
#include "common/gl/surface.hpp"

namespace occ {

GlBackend parse_gl_backend(const std::string& name) {
  if (name == "auto") return GlBackend::Auto;
  if (name == "egl") return GlBackend::Egl;
  if (name == "osmesa") return GlBackend::OSMesa;
  throw InputError("--gl '" + name + "': expected egl, osmesa or auto");
}

namespace {

// llvmpipe's draw module mallocs the shaded vertices of every draw call (hundreds of KB) and frees
// them at its end. Under glibc's defaults such blocks are mmapped and unmapped, or carved from a
// heap top that is trimmed back, per draw: every frame then pays fresh page faults and munmaps, and
// a render process spends much of its time in the kernel (perf shows it). Keeping freed memory in
// the process makes the next draw reuse it. Process-wide, once, before the first context; a user's
// own GLIBC_TUNABLES thresholds win (the glibc.malloc.hugetlb=1 the processes add for themselves,
// common/memory.hpp, is not one: when any malloc tunable turned this off, the heap top was trimmed
// and faulted back, 2 MiB zeroed huge pages at a time, every frame).
void keep_freed_memory() {
  static std::once_flag once;
  std::call_once(once, [] {
    const char* t = std::getenv("GLIBC_TUNABLES");
    if (t && (std::strstr(t, "glibc.malloc.mmap_threshold") || std::strstr(t, "glibc.malloc.trim_threshold"))) return;
    mallopt(M_MMAP_THRESHOLD, 32 << 20);  // glibc's maximum
    mallopt(M_TRIM_THRESHOLD, 256 << 20);
  });
}

}  // namespace

std::unique_ptr<GlContext> GlContext::create(GlBackend backend, int width, int height) {
  keep_freed_memory();
  if (width < 1 || height < 1 || width > kMaxViewportPx || height > kMaxViewportPx)
    throw InputError("framebuffer " + std::to_string(width) + "x" + std::to_string(height) +
                     ": each side must be 1.." + std::to_string(kMaxViewportPx));
  std::string why;
  auto attempt = [&](std::unique_ptr<gl_detail::Surface> (*create_surface)())
      -> std::unique_ptr<GlContext> {
    try {
      return std::unique_ptr<GlContext>(new GlContext(create_surface(), width, height));
    } catch (const std::runtime_error& e) {
      why += (why.empty() ? "" : "; ") + std::string(e.what());
      return nullptr;
    }
  };
  std::unique_ptr<GlContext> ctx;
  if (backend != GlBackend::OSMesa) ctx = attempt(gl_detail::create_egl_surface);
  if (!ctx && backend != GlBackend::Egl) ctx = attempt(gl_detail::create_osmesa_surface);
  if (!ctx) throw std::runtime_error("cannot create an OpenGL 4.5 context: " + why);
  return ctx;
}

GlContext::GlContext(std::unique_ptr<gl_detail::Surface> surface, int width, int height)
    : surface_(std::move(surface)), width_(width), height_(height) {
  gl_.load([this](const char* name) { return surface_->proc_address(name); });
  GLint major = 0, minor = 0;
  gl_.GetIntegerv(GL_MAJOR_VERSION, &major);
  gl_.GetIntegerv(GL_MINOR_VERSION, &minor);
  if (major * 10 + minor < 45)
    throw std::runtime_error(std::string(surface_->name()) + ": OpenGL 4.5 required, got " +
                             version() + " (" + renderer() + ")");

  renderer_class_ = classify_renderer(renderer(), vendor());
  // OCC_RENDERER_CLASS=software|hardware: the defaults of the other class on this renderer (tests
  // of both choices on llvmpipe); anything else is an error naming the variable.
  if (const char* forced = std::getenv("OCC_RENDERER_CLASS"); forced && *forced) {
    const std::string f = forced;
    if (f != "software" && f != "hardware")
      throw std::runtime_error("OCC_RENDERER_CLASS=" + f + ": must be software or hardware");
    renderer_class_ = f == "software" ? RendererClass::software : RendererClass::hardware;
  }

  gl_.CreateRenderbuffers(1, &color_rb_);
  gl_.NamedRenderbufferStorage(color_rb_, GL_RGBA8, width, height);
  // Depth is a texture, not a renderbuffer, so that compute shaders can read it (the HC depth
  // pyramid, hzb_query.hpp); rendering into it is the same.
  gl_.CreateTextures(GL_TEXTURE_2D, 1, &depth_tex_);
  gl_.TextureStorage2D(depth_tex_, 1, GL_DEPTH_COMPONENT32F, width, height);
  gl_.CreateFramebuffers(1, &fbo_);
  gl_.NamedFramebufferRenderbuffer(fbo_, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, color_rb_);
  gl_.NamedFramebufferTexture(fbo_, GL_DEPTH_ATTACHMENT, depth_tex_, 0);
  gl_.NamedFramebufferReadBuffer(fbo_, GL_COLOR_ATTACHMENT0);
  const GLenum status = gl_.CheckNamedFramebufferStatus(fbo_, GL_FRAMEBUFFER);
  if (status != GL_FRAMEBUFFER_COMPLETE) {
    char buf[96];
    std::snprintf(buf, sizeof buf, ": framebuffer %dx%d incomplete (status 0x%04x)", width,
                  height, unsigned(status));
    throw std::runtime_error(surface_->name() + std::string(buf));
  }
  bind_framebuffer();

  // Reverse-Z for Camera::projection(): near -> 1, far -> 0.
  gl_.ClipControl(GL_LOWER_LEFT, GL_ZERO_TO_ONE);
  gl_.Enable(GL_DEPTH_TEST);
  gl_.DepthFunc(GL_GREATER);
  gl_.ClearDepth(0.0);
  gl_.PixelStorei(GL_PACK_ALIGNMENT, 1);
  if (GLenum err = gl_.GetError(); err != GL_NO_ERROR) {
    char buf[64];
    std::snprintf(buf, sizeof buf, ": GL error 0x%04x during setup", unsigned(err));
    throw std::runtime_error(surface_->name() + std::string(buf));
  }
}

// Destroying the native context frees the framebuffer and everything else it owns.
GlContext::~GlContext() = default;

std::string GlContext::renderer() const {
  return reinterpret_cast<const char*>(gl_.GetString(GL_RENDERER));
}

std::string GlContext::version() const {
  return reinterpret_cast<const char*>(gl_.GetString(GL_VERSION));
}

std::string GlContext::vendor() const {
  return reinterpret_cast<const char*>(gl_.GetString(GL_VENDOR));
}

const char* GlContext::backend_name() const { return surface_->name(); }

void GlContext::make_current() {
  surface_->make_current();
  bind_framebuffer();
}

void GlContext::release_current() { surface_->release_current(); }

void GlContext::bind_framebuffer() const {
  gl_.BindFramebuffer(GL_FRAMEBUFFER, fbo_);
  gl_.Viewport(0, 0, width_, height_);
}

Image GlContext::read_rgba() const {
  Image img;
  img.width = width_;
  img.height = height_;
  img.rgba.resize(size_t(width_) * height_ * 4);
  gl_.ReadPixels(0, 0, width_, height_, GL_RGBA, GL_UNSIGNED_BYTE, img.rgba.data());
  const size_t row = size_t(width_) * 4;  // GL's first row is the bottom one
  for (int y = 0; y < height_ / 2; ++y)
    std::swap_ranges(img.rgba.begin() + y * row, img.rgba.begin() + (y + 1) * row,
                     img.rgba.end() - (y + 1) * row);
  return img;
}

std::vector<float> GlContext::read_depth() const {
  std::vector<float> depth(size_t(width_) * height_);
  read_depth(depth.data());
  return depth;
}

void GlContext::read_depth(float* out) const {
  gl_.ReadPixels(0, 0, width_, height_, GL_DEPTH_COMPONENT, GL_FLOAT, out);
}

void GlContext::write_depth(const float* depth) {
  gl_.PixelStorei(GL_UNPACK_ALIGNMENT, 4);
  gl_.TextureSubImage2D(depth_tex_, 0, 0, 0, width_, height_, GL_DEPTH_COMPONENT, GL_FLOAT, depth);
}

void GlContext::read_depth(int x, int y, int w, int h, float* out) const {
  gl_.PixelStorei(GL_PACK_ROW_LENGTH, width_);
  gl_.ReadPixels(x, y, w, h, GL_DEPTH_COMPONENT, GL_FLOAT, out + size_t(y) * size_t(width_) + size_t(x));
  gl_.PixelStorei(GL_PACK_ROW_LENGTH, 0);
}

}  // namespace occ
