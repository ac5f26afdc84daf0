// Internal to occ_gl: the window-system half of a GlContext back end. A Surface owns a native
// context (EGL or OSMesa) that was created current on the calling thread; the GL side
// (framebuffer object, state) lives in GlContext.
#pragma once
#include <memory>

namespace occ::gl_detail {

class Surface {
 public:
  virtual ~Surface() = default;
  virtual const char* name() const = 0;
  virtual void make_current() = 0;
  virtual void release_current() = 0;
  virtual void* proc_address(const char* name) const = 0;
};

// Each throws std::runtime_error with the reason (every sub-attempt for EGL) on failure.
std::unique_ptr<Surface> create_egl_surface();
std::unique_ptr<Surface> create_osmesa_surface();

}  // namespace occ::gl_detail
