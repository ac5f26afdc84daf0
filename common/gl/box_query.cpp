#include "common/gl/box_query.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

#include <glm/gtc/type_ptr.hpp>

#include "common/gl/shader.hpp"

namespace occ {
namespace {

// Corner c of the box is (c & 1, c >> 1 & 1, c >> 2 & 1) between min and max; 6 faces x 2
// triangles, each counter-clockwise seen from outside the box (faces -z, +z, -y, +y, -x, +x).
const char* const kBoxVertex = R"(#version 450 core
uniform mat4 u_view_projection;
uniform vec3 u_min;
uniform vec3 u_max;
const int kCorners[36] = int[36](0, 3, 1, 0, 2, 3,  4, 7, 6, 4, 5, 7,  0, 5, 4, 0, 1, 5,
                                 2, 7, 3, 2, 6, 7,  0, 6, 2, 0, 4, 6,  1, 7, 5, 1, 3, 7);
void main() {
  int c = kCorners[gl_VertexID];
  bvec3 upper = bvec3((c & 1) != 0, (c & 2) != 0, (c & 4) != 0);
  gl_Position = u_view_projection * vec4(mix(u_min, u_max, upper), 1.0);
}
)";

const char* const kBoxFragment = R"(#version 450 core
void main() {}
)";

}  // namespace

BoxQuerier::BoxQuerier(GlContext& ctx) : gl_(ctx.gl()) {
  program_ = link_program(gl_, kBoxVertex, kBoxFragment);
  view_projection_loc_ = gl_.GetUniformLocation(program_, "u_view_projection");
  min_loc_ = gl_.GetUniformLocation(program_, "u_min");
  max_loc_ = gl_.GetUniformLocation(program_, "u_max");
  gl_.CreateVertexArrays(1, &vao_);  // no attributes: corners come from gl_VertexID
}

BoxQuerier::~BoxQuerier() {
  if (!pool_.empty()) gl_.DeleteQueries(GLsizei(pool_.size()), pool_.data());
  gl_.DeleteVertexArrays(1, &vao_);
  gl_.DeleteProgram(program_);
}

void BoxQuerier::begin(const Camera& cam) {
  eye_ = cam.eye;
  // As visible_without_query, with more slack: the GPU box is padded and rounded to float.
  const double ty = std::tan(cam.fovy_rad * 0.5), tx = ty * cam.aspect;
  reach_ = cam.near_dist * std::sqrt(1.0 + tx * tx + ty * ty) * (1.0 + 1e-3);
  const glm::mat4 view_projection(cam.projection() * cam.view_rotation());
  gl_.ProgramUniformMatrix4fv(program_, view_projection_loc_, 1, GL_FALSE, glm::value_ptr(view_projection));
  gl_.UseProgram(program_);
  gl_.BindVertexArray(vao_);
  gl_.ColorMask(GL_FALSE, GL_FALSE, GL_FALSE, GL_FALSE);
  gl_.DepthMask(GL_FALSE);
  gl_.Enable(GL_DEPTH_TEST);
  gl_.DepthFunc(GL_GREATER);
  gl_.Enable(GL_CULL_FACE);
  gl_.CullFace(GL_BACK);
  gl_.FrontFace(GL_CCW);
}

uint32_t BoxQuerier::issue(const Aabb& box) {
  if (next_ == pool_.size()) {
    const size_t old = pool_.size();
    pool_.resize(old + 64);
    gl_.CreateQueries(GL_SAMPLES_PASSED, 64, pool_.data() + old);
  }
  const uint32_t handle = next_++;
  ++queries_issued_;
  gl_.BeginQuery(GL_SAMPLES_PASSED, pool_[handle]);
  if (!box.empty()) {
    const glm::dvec3 lo = box.min - eye_, hi = box.max - eye_;
    const glm::dvec3 far = glm::max(glm::abs(lo), glm::abs(hi));
    const double pad = kRelativePad * std::max({far.x, far.y, far.z});
    gl_.ProgramUniform3f(program_, min_loc_, float(lo.x - pad), float(lo.y - pad), float(lo.z - pad));
    gl_.ProgramUniform3f(program_, max_loc_, float(hi.x + pad), float(hi.y + pad), float(hi.z + pad));
    // The padded box within reach of the near rectangle: its front faces may be clipped where
    // the back faces are not (or the eye may be inside it): draw both sides, as without culling.
    const glm::dvec3 gap = glm::max(glm::max(lo - pad, -(hi + pad)), glm::dvec3(0.0));
    const bool near = glm::dot(gap, gap) <= reach_ * reach_;
    if (near) gl_.Disable(GL_CULL_FACE);
    gl_.DrawArrays(GL_TRIANGLES, 0, 36);
    if (near) gl_.Enable(GL_CULL_FACE);
  }
  gl_.EndQuery(GL_SAMPLES_PASSED);
  return handle;
}

uint64_t BoxQuerier::result(uint32_t handle) {
  if (handle >= next_)
    throw std::out_of_range("BoxQuerier: query handle " + std::to_string(handle) +
                            " not issued in this batch (" + std::to_string(next_) + " issued)");
  GLuint64 samples = 0;
  gl_.GetQueryObjectui64v(pool_[handle], GL_QUERY_RESULT, &samples);
  return samples;
}

bool BoxQuerier::ready(uint32_t handle) const {
  if (handle >= next_) throw std::out_of_range("BoxQuerier: query handle not issued in this batch");
  GLuint64 available = 0;
  gl_.GetQueryObjectui64v(pool_[handle], GL_QUERY_RESULT_AVAILABLE, &available);
  return available != 0;
}

void BoxQuerier::reset() { next_ = 0; }

void BoxQuerier::end() {
  gl_.ColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
  gl_.DepthMask(GL_TRUE);
  gl_.Disable(GL_CULL_FACE);
}

}  // namespace occ
