#include "common/gl/box_overlay.hpp"

#include <glm/gtc/type_ptr.hpp>

#include "common/gl/box_query.hpp"
#include "common/gl/shader.hpp"

namespace occ {
namespace {

const char* const kFragment = R"(#version 450 core
out vec4 o_colour;
void main() { o_colour = vec4(1.0, 110.0 / 255.0, 0.0, 0.3); }
)";

}  // namespace

BoxOverlay::BoxOverlay(GlContext& ctx) : gl_(ctx.gl()) {
  program_ = link_program(gl_, kBoxVertexShader, kFragment);
  view_projection_loc_ = gl_.GetUniformLocation(program_, "u_view_projection");
  min_loc_ = gl_.GetUniformLocation(program_, "u_min");
  max_loc_ = gl_.GetUniformLocation(program_, "u_max");
  gl_.CreateVertexArrays(1, &vao_);
}

BoxOverlay::~BoxOverlay() {
  gl_.DeleteVertexArrays(1, &vao_);
  gl_.DeleteProgram(program_);
}

void BoxOverlay::draw(const Camera& cam, std::span<const Aabb> boxes) {
  const glm::mat4 view_projection(cam.projection() * cam.view_rotation());
  gl_.ProgramUniformMatrix4fv(program_, view_projection_loc_, 1, GL_FALSE, glm::value_ptr(view_projection));
  gl_.UseProgram(program_);
  gl_.BindVertexArray(vao_);
  gl_.Disable(GL_DEPTH_TEST);
  gl_.DepthMask(GL_FALSE);
  gl_.Enable(GL_CULL_FACE);
  gl_.CullFace(GL_BACK);
  gl_.FrontFace(GL_CCW);
  gl_.Enable(GL_BLEND);
  gl_.BlendFuncSeparate(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA, GL_ZERO, GL_ONE);
  for (const Aabb& box : boxes) {
    if (box.empty()) continue;
    const glm::dvec3 lo = box.min - cam.eye, hi = box.max - cam.eye;  // camera-relative, as everywhere
    gl_.ProgramUniform3f(program_, min_loc_, float(lo.x), float(lo.y), float(lo.z));
    gl_.ProgramUniform3f(program_, max_loc_, float(hi.x), float(hi.y), float(hi.z));
    gl_.DrawArrays(GL_TRIANGLES, 0, 36);
  }
  gl_.Disable(GL_BLEND);
  gl_.Disable(GL_CULL_FACE);
  gl_.DepthMask(GL_TRUE);
  gl_.Enable(GL_DEPTH_TEST);
}

}  // namespace occ
