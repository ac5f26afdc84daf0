// OSMesa back end (Mesa's off-screen software rasteriser). A separate file because <GL/osmesa.h>
// includes the legacy <GL/gl.h>, which must not meet <GL/glcorearb.h>. OSMesa insists on a
// client colour buffer for its default framebuffer; a 1x1 one suffices since GlContext draws
// into its own framebuffer object.
#include <GL/osmesa.h>

#include <cstdint>
#include <stdexcept>

#include "common/gl/surface.hpp"

namespace occ::gl_detail {
namespace {

class OSMesaSurface final : public Surface {
 public:
  explicit OSMesaSurface(OSMesaContext context) : context_(context) {}
  ~OSMesaSurface() override {
    if (OSMesaGetCurrentContext() == context_) release_current();
    OSMesaDestroyContext(context_);
  }
  const char* name() const override { return "osmesa"; }
  void make_current() override {
    if (!OSMesaMakeCurrent(context_, pixel_, GL_UNSIGNED_BYTE, 1, 1))
      throw std::runtime_error("OSMesaMakeCurrent failed");
  }
  void release_current() override { OSMesaMakeCurrent(nullptr, nullptr, 0, 0, 0); }
  void* proc_address(const char* name) const override {
    return reinterpret_cast<void*>(OSMesaGetProcAddress(name));
  }

 private:
  OSMesaContext context_;
  uint32_t pixel_[1] = {};
};

}  // namespace

std::unique_ptr<Surface> create_osmesa_surface() {
  for (int minor : {6, 5}) {
    const int attribs[] = {OSMESA_FORMAT, OSMESA_RGBA, OSMESA_DEPTH_BITS, 0,
                           OSMESA_STENCIL_BITS, 0, OSMESA_ACCUM_BITS, 0,
                           OSMESA_PROFILE, OSMESA_CORE_PROFILE,
                           OSMESA_CONTEXT_MAJOR_VERSION, 4, OSMESA_CONTEXT_MINOR_VERSION, minor,
                           0};
    OSMesaContext context = OSMesaCreateContextAttribs(attribs, nullptr);
    if (!context) continue;
    auto surface = std::make_unique<OSMesaSurface>(context);
    surface->make_current();
    return surface;
  }
  throw std::runtime_error("OSMesa: no OpenGL 4.5 core context");
}

}  // namespace occ::gl_detail
