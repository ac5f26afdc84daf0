#include "common/gl/shader.hpp"

#include <algorithm>
#include <initializer_list>
#include <stdexcept>

namespace occ {
namespace {

// The driver's info log of a shader or program (GetShaderiv + GetShaderInfoLog, or the
// Program pair), up to its first NUL.
template <class GetIv, class GetLog>
std::string info_log(GLuint object, GetIv get_iv, GetLog get_log) {
  GLint len = 0;
  get_iv(object, GL_INFO_LOG_LENGTH, &len);
  std::string log(size_t(std::max(len, 1)), '\0');
  get_log(object, len, nullptr, log.data());
  return log.c_str();
}

GLuint compile(const GlApi& gl, GLenum stage, const std::string& src) {
  GLuint sh = gl.CreateShader(stage);
  const char* text = src.c_str();
  gl.ShaderSource(sh, 1, &text, nullptr);
  gl.CompileShader(sh);
  GLint ok = GL_FALSE;
  gl.GetShaderiv(sh, GL_COMPILE_STATUS, &ok);
  if (!ok) {
    const std::string log = info_log(sh, gl.GetShaderiv, gl.GetShaderInfoLog);
    gl.DeleteShader(sh);
    throw std::runtime_error(std::string(stage == GL_VERTEX_SHADER     ? "vertex"
                                         : stage == GL_COMPUTE_SHADER ? "compute"
                                                                      : "fragment") +
                             " shader does not compile: " + log);
  }
  return sh;
}

GLuint link(const GlApi& gl, std::initializer_list<GLuint> shaders) {
  GLuint prog = gl.CreateProgram();
  for (GLuint sh : shaders) gl.AttachShader(prog, sh);
  gl.LinkProgram(prog);
  for (GLuint sh : shaders) gl.DeleteShader(sh);  // flagged for deletion; freed with the program
  GLint ok = GL_FALSE;
  gl.GetProgramiv(prog, GL_LINK_STATUS, &ok);
  if (!ok) {
    const std::string log = info_log(prog, gl.GetProgramiv, gl.GetProgramInfoLog);
    gl.DeleteProgram(prog);
    throw std::runtime_error("program does not link: " + log);
  }
  return prog;
}

}  // namespace

GLuint link_program(const GlApi& gl, const std::string& vertex_src, const std::string& fragment_src) {
  GLuint vs = compile(gl, GL_VERTEX_SHADER, vertex_src);
  GLuint fs = 0;
  try {
    fs = compile(gl, GL_FRAGMENT_SHADER, fragment_src);
  } catch (...) {
    gl.DeleteShader(vs);
    throw;
  }
  return link(gl, {vs, fs});
}

GLuint link_compute_program(const GlApi& gl, const std::string& compute_src) {
  return link(gl, {compile(gl, GL_COMPUTE_SHADER, compute_src)});
}

}  // namespace occ
