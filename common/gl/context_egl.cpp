// EGL back end: the EGL device platform's hardware devices first (a GPU driver), then Mesa's
// surfaceless platform, then a software device (Mesa's llvmpipe). Surfaceless contexts only
// (EGL_KHR_surfaceless_context): GlContext renders into its own framebuffer object. Linked
// against libEGL alone (libglvnd's on Debian); GL entry points come from eglGetProcAddress.
#include <EGL/egl.h>
#include <EGL/eglext.h>

#include <cstdio>
#include <cstring>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/gl/surface.hpp"

namespace occ::gl_detail {
namespace {

std::string egl_error() {
  char buf[32];
  std::snprintf(buf, sizeof buf, "EGL error 0x%04x", unsigned(eglGetError()));
  return buf;
}

bool has_extension(const char* list, const char* ext) {
  if (!list) return false;
  const size_t n = std::strlen(ext);
  for (const char* p = list; (p = std::strstr(p, ext)) != nullptr; p += n)
    if ((p == list || p[-1] == ' ') && (p[n] == ' ' || p[n] == '\0')) return true;
  return false;
}

class EglSurface final : public Surface {
 public:
  EglSurface(EGLDisplay display, EGLContext context, const char* name)
      : display_(display), context_(context), name_(name) {}
  // The display is deliberately not terminated: EGL displays are shared per process (another
  // GlContext may use the same one), and eglTerminate would destroy its contexts too.
  ~EglSurface() override {
    if (eglGetCurrentContext() == context_) release_current();
    eglDestroyContext(display_, context_);
  }
  const char* name() const override { return name_; }
  void make_current() override {
    eglBindAPI(EGL_OPENGL_API);  // the bound API is per thread
    if (!eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, context_))
      throw std::runtime_error("eglMakeCurrent failed: " + egl_error());
  }
  void release_current() override {
    eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
  }
  void* proc_address(const char* name) const override {
    return reinterpret_cast<void*>(eglGetProcAddress(name));
  }

 private:
  EGLDisplay display_;
  EGLContext context_;
  const char* name_;
};

// An OpenGL core context (4.6, else 4.5: the oldest version this code runs on) on `display`,
// made current without a surface.
std::unique_ptr<Surface> create_on(EGLDisplay display, const char* name) {
  if (display == EGL_NO_DISPLAY) throw std::runtime_error("no display: " + egl_error());
  EGLint major = 0, minor = 0;
  if (!eglInitialize(display, &major, &minor))
    throw std::runtime_error("eglInitialize failed: " + egl_error());
  if (!has_extension(eglQueryString(display, EGL_EXTENSIONS), "EGL_KHR_surfaceless_context"))
    throw std::runtime_error("no EGL_KHR_surfaceless_context");
  if (!eglBindAPI(EGL_OPENGL_API)) throw std::runtime_error("no OpenGL API: " + egl_error());
  const EGLint config_attribs[] = {EGL_SURFACE_TYPE, 0, EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT,
                                   EGL_NONE};
  EGLConfig config = nullptr;
  EGLint configs = 0;
  if (!eglChooseConfig(display, config_attribs, &config, 1, &configs) || configs < 1)
    throw std::runtime_error("no OpenGL config: " + egl_error());
  for (auto [want_major, want_minor] : {std::pair{4, 6}, std::pair{4, 5}}) {
    const EGLint attribs[] = {EGL_CONTEXT_MAJOR_VERSION, want_major,
                              EGL_CONTEXT_MINOR_VERSION, want_minor,
                              EGL_CONTEXT_OPENGL_PROFILE_MASK, EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT,
                              EGL_NONE};
    EGLContext context = eglCreateContext(display, config, EGL_NO_CONTEXT, attribs);
    if (context == EGL_NO_CONTEXT) continue;
    auto surface = std::make_unique<EglSurface>(display, context, name);
    surface->make_current();
    return surface;
  }
  throw std::runtime_error("no OpenGL 4.5 core context: " + egl_error());
}

// The device platform's devices, hardware first: a device of Mesa's software rasteriser
// (EGL_MESA_device_software) goes to `software`, every other one (a GPU driver) to `hardware`.
void query_devices(const char* client, std::vector<EGLDeviceEXT>& hardware, std::vector<EGLDeviceEXT>& software,
                   std::string& why) {
  auto query = reinterpret_cast<PFNEGLQUERYDEVICESEXTPROC>(eglGetProcAddress("eglQueryDevicesEXT"));
  auto device_string =
      reinterpret_cast<PFNEGLQUERYDEVICESTRINGEXTPROC>(eglGetProcAddress("eglQueryDeviceStringEXT"));
  EGLDeviceEXT devices[16];
  EGLint count = 0;
  if (!has_extension(client, "EGL_EXT_platform_device") || !query) {
    why += "; no EGL_EXT_platform_device / EGL_EXT_device_enumeration";
    return;
  }
  if (!query(16, devices, &count) || count == 0) {
    why += "; device platform: no devices";
    return;
  }
  for (EGLint i = 0; i < count; ++i) {
    // Without EGL_EXT_device_query a device cannot tell what it is: tried after surfaceless.
    const char* ext = device_string ? device_string(devices[i], EGL_EXTENSIONS) : nullptr;
    const bool is_software = !device_string || has_extension(ext, "EGL_MESA_device_software");
    (is_software ? software : hardware).push_back(devices[i]);
  }
}

// The first of `devices` that gives a context, or null (each failure appended to `why`).
std::unique_ptr<Surface> create_on_devices(PFNEGLGETPLATFORMDISPLAYEXTPROC get_display,
                                           const std::vector<EGLDeviceEXT>& devices, const char* kind,
                                           std::string& why) {
  for (size_t i = 0; i < devices.size(); ++i) {
    try {
      return create_on(get_display(EGL_PLATFORM_DEVICE_EXT, devices[i], nullptr), "egl-device");
    } catch (const std::runtime_error& e) {
      why += std::string("; ") + kind + " device " + std::to_string(i) + ": " + e.what();
    }
  }
  return nullptr;
}

}  // namespace

// A hardware GPU's device first (the EGL device platform: what a GPU machine with only its
// driver and libglvnd has), then Mesa's surfaceless platform, then a software device.
std::unique_ptr<Surface> create_egl_surface() {
  const char* client = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
  auto get_display = reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(
      eglGetProcAddress("eglGetPlatformDisplayEXT"));
  if (!client || !get_display) throw std::runtime_error("EGL: no client extensions / eglGetPlatformDisplayEXT");
  std::string why;
  std::vector<EGLDeviceEXT> hardware, software;
  query_devices(client, hardware, software, why);
  if (auto s = create_on_devices(get_display, hardware, "GPU", why)) return s;
  if (has_extension(client, "EGL_MESA_platform_surfaceless")) {
    try {
      return create_on(get_display(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr),
                       "egl-surfaceless");
    } catch (const std::runtime_error& e) {
      why += std::string("; surfaceless platform: ") + e.what();
    }
  } else {
    why += "; no EGL_MESA_platform_surfaceless";
  }
  if (auto s = create_on_devices(get_display, software, "software", why)) return s;
  throw std::runtime_error("EGL: " + why.substr(why.empty() ? 0 : 2));
}

}  // namespace occ::gl_detail
