// Compiling and linking GLSL programs. Errors throw std::runtime_error with the stage and the
// driver's info log; the sources are internal, so a failure is a bug or an unsupported driver.
#pragma once
#include <string>

#include "common/gl/gl_api.hpp"

namespace occ {

// Links a program from vertex and fragment shader sources (full text including #version).
GLuint link_program(const GlApi& gl, const std::string& vertex_src, const std::string& fragment_src);
// Links a program from one compute shader source.
GLuint link_compute_program(const GlApi& gl, const std::string& compute_src);

}  // namespace occ
