#include "common/gl/gl_api.hpp"

#include <stdexcept>

namespace occ {

void GlApi::load(const std::function<void*(const char*)>& getproc) {
#define OCC_GL_LOAD(upper, name)                                                    \
  name = reinterpret_cast<PFNGL##upper##PROC>(getproc("gl" #name));                 \
  if (!name) throw std::runtime_error("OpenGL entry point gl" #name " is missing");
  OCC_GL_FUNCTIONS(OCC_GL_LOAD)
#undef OCC_GL_LOAD
}

}  // namespace occ
