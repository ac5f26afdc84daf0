// OSMesa back end (Mesa's off-screen software rasteriser). A separate file because <GL/osmesa.h>
// includes the legacy <GL/gl.h>, which must not meet <GL/glcorearb.h>. OSMesa insists on a
// client colour buffer for its default framebuffer; a 1x1 one suffices since GlContext draws
// into its own framebuffer object. libOSMesa is loaded when first asked for (dlopen; it pulls in
// libLLVM, which a GPU machine lacks): $OCC_OSMESA_LIBRARY names another file, and one that
// does not exist makes it unloadable (tests).
#include <GL/osmesa.h>

#include <cstdint>
#include <stdexcept>

#include "common/gl/dynamic_library.hpp"
#include "common/gl/surface.hpp"

namespace occ::gl_detail {
namespace {

// The OSMesa entry points used here, loaded once per process.
struct OSMesaApi {
  DynamicLibrary lib{"the OSMesa library", "libOSMesa.so.8", "OCC_OSMESA_LIBRARY",
                     "install Mesa's OSMesa (Debian: libosmesa6; scripts/setup.sh) or use --gl egl"};
#define OCC_OSMESA_ENTRY(fn) decltype(&::fn) fn = lib.symbol<decltype(&::fn)>(#fn);
  OCC_OSMESA_ENTRY(OSMesaCreateContextAttribs)
  OCC_OSMESA_ENTRY(OSMesaDestroyContext)
  OCC_OSMESA_ENTRY(OSMesaMakeCurrent)
  OCC_OSMESA_ENTRY(OSMesaGetCurrentContext)
  OCC_OSMESA_ENTRY(OSMesaGetProcAddress)
#undef OCC_OSMESA_ENTRY
};

// Throws the loading error on every call until the library loads (a failed static initialisation
// is retried).
const OSMesaApi& osmesa() {
  static const OSMesaApi api;
  return api;
}

class OSMesaSurface final : public Surface {
 public:
  OSMesaSurface(const OSMesaApi& api, OSMesaContext context) : api_(api), context_(context) {}
  ~OSMesaSurface() override {
    if (api_.OSMesaGetCurrentContext() == context_) release_current();
    api_.OSMesaDestroyContext(context_);
  }
  const char* name() const override { return "osmesa"; }
  void make_current() override {
    if (!api_.OSMesaMakeCurrent(context_, pixel_, GL_UNSIGNED_BYTE, 1, 1))
      throw std::runtime_error("OSMesaMakeCurrent failed");
  }
  void release_current() override { api_.OSMesaMakeCurrent(nullptr, nullptr, 0, 0, 0); }
  void* proc_address(const char* name) const override {
    return reinterpret_cast<void*>(api_.OSMesaGetProcAddress(name));
  }

 private:
  const OSMesaApi& api_;
  OSMesaContext context_;
  uint32_t pixel_[1] = {};
};

}  // namespace

std::unique_ptr<Surface> create_osmesa_surface() {
  const OSMesaApi& api = osmesa();
  for (int minor : {6, 5}) {
    const int attribs[] = {OSMESA_FORMAT, OSMESA_RGBA, OSMESA_DEPTH_BITS, 0,
                           OSMESA_STENCIL_BITS, 0, OSMESA_ACCUM_BITS, 0,
                           OSMESA_PROFILE, OSMESA_CORE_PROFILE,
                           OSMESA_CONTEXT_MAJOR_VERSION, 4, OSMESA_CONTEXT_MINOR_VERSION, minor,
                           0};
    OSMesaContext context = api.OSMesaCreateContextAttribs(attribs, nullptr);
    if (!context) continue;
    auto surface = std::make_unique<OSMesaSurface>(api, context);
    surface->make_current();
    return surface;
  }
  throw std::runtime_error("OSMesa: no OpenGL 4.5 core context");
}

}  // namespace occ::gl_detail
