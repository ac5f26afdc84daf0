#include "common/gl/box_query.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include <glm/gtc/type_ptr.hpp>

#include "common/gl/shader.hpp"

namespace occ {
namespace {

}  // namespace

// Corner c of the box is (c & 1, c >> 1 & 1, c >> 2 & 1) between min and max; 6 faces x 2
// triangles, each counter-clockwise seen from outside the box (faces -z, +z, -y, +y, -x, +x).
const char* const kBoxVertexShader = R"(#version 450 core
uniform mat4 u_view_projection;
uniform vec3 u_min;
uniform vec3 u_max;
out float gl_ClipDistance[6];  // boxes are never clipped by section planes (conservative)
const int kCorners[36] = int[36](0, 3, 1, 0, 2, 3,  4, 7, 6, 4, 5, 7,  0, 5, 4, 0, 1, 5,
                                 2, 7, 3, 2, 6, 7,  0, 6, 2, 0, 4, 6,  1, 7, 5, 1, 3, 7);
void main() {
  int c = kCorners[gl_VertexID];
  bvec3 upper = bvec3((c & 1) != 0, (c & 2) != 0, (c & 4) != 0);
  gl_Position = u_view_projection * vec4(mix(u_min, u_max, upper), 1.0);
  for (int i = 0; i < 6; ++i) gl_ClipDistance[i] = 1.0;
}
)";

namespace {

const char* const kBoxFragment = R"(#version 450 core
void main() {}
)";

// BoxBatchCounter: the same boxes (same corners, same triangles), read from a buffer, box
// u_first + gl_VertexID / 36; every fragment that passes the depth test (early fragment tests: the
// shader runs only for those) adds one to its box's count.
const char* const kBatchVertex = R"(#version 450 core
uniform mat4 u_view_projection;
uniform int u_first;
layout(std430, binding = 2) readonly buffer Boxes { vec4 boxes[]; };  // min, max per box
flat out int v_box;
out float gl_ClipDistance[6];  // boxes are never clipped by section planes (conservative)
const int kCorners[36] = int[36](0, 3, 1, 0, 2, 3,  4, 7, 6, 4, 5, 7,  0, 5, 4, 0, 1, 5,
                                 2, 7, 3, 2, 6, 7,  0, 6, 2, 0, 4, 6,  1, 7, 5, 1, 3, 7);
void main() {
  int b = u_first + gl_VertexID / 36;
  int c = kCorners[gl_VertexID % 36];
  bvec3 upper = bvec3((c & 1) != 0, (c & 2) != 0, (c & 4) != 0);
  v_box = b;
  gl_Position = u_view_projection * vec4(mix(boxes[2 * b].xyz, boxes[2 * b + 1].xyz, upper), 1.0);
  for (int i = 0; i < 6; ++i) gl_ClipDistance[i] = 1.0;
}
)";

// EXACT: every fragment adds one (atomically); otherwise the first ones set the count to 1 (a load
// per fragment, a store while it reads 0: far cheaper for boxes that cover much of the screen).
const char* const kBatchFragment = R"(
layout(early_fragment_tests) in;
flat in int v_box;
layout(std430, binding = 3) buffer Counts { uint counts[]; };
void main() {
#ifdef EXACT
  atomicAdd(counts[v_box], 1u);
#else
  if (counts[v_box] == 0u) counts[v_box] = 1u;
#endif
}
)";

// The box as both classes draw it: camera-relative, padded, rounded to float; `near` when the
// padded box is within reach of the near rectangle (not drawn then: it counts as visible).
//
// The pad is the larger of a relative epsilon (float rounding of the corners) and
// BoxQuerier::kPadSubpixels sub-pixel steps at the distance of the box's farthest corner: moving
// every corner outwards by `pad` on each axis moves each silhouette edge at least `pad` across
// the view ray, i.e. at least that many sub-pixel steps on screen. Without it, a face of the content seen nearly
// edge-on whose edge the rasteriser snaps onto a pixel centre (sub-pixel grid, tie rules) can
// cover that pixel while the box's own edge, a thousandth of a pixel outside, does not: a
// one-pixel sliver went missing (city:6x6:3:10:1, docs/hard_cases.md).
struct DrawnBox {
  glm::vec3 lo, hi;
  bool near;
};
DrawnBox drawn_box(const Aabb& box, const glm::dvec3& eye, double reach, double pad_per_distance) {
  const glm::dvec3 lo = box.min - eye, hi = box.max - eye;
  const glm::dvec3 far = glm::max(glm::abs(lo), glm::abs(hi));
  const double pad = std::max(BoxQuerier::kRelativePad * std::max({far.x, far.y, far.z}),
                              pad_per_distance * glm::length(far));
  const glm::dvec3 gap = glm::max(glm::max(lo - pad, -(hi + pad)), glm::dvec3(0.0));
  return {glm::vec3(float(lo.x - pad), float(lo.y - pad), float(lo.z - pad)),
          glm::vec3(float(hi.x + pad), float(hi.y + pad), float(hi.z + pad)), glm::dot(gap, gap) <= reach * reach};
}

// As visible_without_query, with more slack: the GPU box is padded and rounded to float.
double near_reach(const Camera& cam) {
  const double ty = std::tan(cam.fovy_rad * 0.5), tx = ty * cam.aspect;
  return cam.near_dist * std::sqrt(1.0 + tx * tx + ty * ty) * (1.0 + 1e-3);
}

// One step of the rasteriser's sub-pixel grid in pixels (GL_SUBPIXEL_BITS, at least 4 by the GL
// spec; 8 on llvmpipe). A constant of the implementation: read once per querier.
double subpixel_step(const GlApi& gl) {
  GLint bits = 4;
  gl.GetIntegerv(GL_SUBPIXEL_BITS, &bits);
  return 1.0 / double(1u << std::clamp(bits, 1, 16));
}

// The pad in world units per unit of distance from the eye: kPadSubpixels sub-pixel steps (1/64
// px on llvmpipe) for a viewport `viewport_height` pixels tall.
double pad_per_unit_distance(const Camera& cam, double step, int viewport_height) {
  return BoxQuerier::kPadSubpixels * step * 2.0 * std::tan(cam.fovy_rad * 0.5) / std::max(1, viewport_height);
}

// Colour and depth writes off, reverse-Z depth test, back faces culled.
void query_state(const GlApi& gl, GLuint program, GLuint vao) {
  gl.UseProgram(program);
  gl.BindVertexArray(vao);
  gl.ColorMask(GL_FALSE, GL_FALSE, GL_FALSE, GL_FALSE);
  gl.DepthMask(GL_FALSE);
  gl.Enable(GL_DEPTH_TEST);
  gl.DepthFunc(GL_GREATER);
  gl.Enable(GL_CULL_FACE);
  gl.CullFace(GL_BACK);
  gl.FrontFace(GL_CCW);
}

}  // namespace

void BoxDrawState::create(const GlApi& gl, GLuint linked_program) {
  program = linked_program;
  view_projection_loc = gl.GetUniformLocation(program, "u_view_projection");
  gl.CreateVertexArrays(1, &vao);  // no attributes: corners come from gl_VertexID
  subpixel_step = occ::subpixel_step(gl);
}

void BoxDrawState::destroy(const GlApi& gl) {
  gl.DeleteVertexArrays(1, &vao);
  gl.DeleteProgram(program);
}

void BoxDrawState::begin(const GlApi& gl, const Camera& cam) {
  eye = cam.eye;
  reach = near_reach(cam);
  GLint viewport[4] = {0, 0, 0, 0};
  gl.GetIntegerv(GL_VIEWPORT, viewport);
  pixel_pad = pad_per_unit_distance(cam, subpixel_step, viewport[3]);
  pixels = uint64_t(std::max(viewport[2], 1)) * uint64_t(std::max(viewport[3], 1));
  const glm::mat4 view_projection(cam.projection() * cam.view_rotation());
  gl.ProgramUniformMatrix4fv(program, view_projection_loc, 1, GL_FALSE, glm::value_ptr(view_projection));
  query_state(gl, program, vao);
}

BoxTester::BoxTester(GlContext& ctx, GLuint linked_program) : gl_(ctx.gl()) { box_.create(gl_, linked_program); }

BoxTester::~BoxTester() { box_.destroy(gl_); }

void BoxTester::end() {
  gl_.ColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
  gl_.DepthMask(GL_TRUE);
  gl_.Disable(GL_CULL_FACE);
}

BoxQuerier::BoxQuerier(GlContext& ctx) : BoxTester(ctx, link_program(ctx.gl(), kBoxVertexShader, kBoxFragment)) {
  min_loc_ = gl_.GetUniformLocation(box_.program, "u_min");
  max_loc_ = gl_.GetUniformLocation(box_.program, "u_max");
}

BoxQuerier::~BoxQuerier() {
  if (!pool_.empty()) gl_.DeleteQueries(GLsizei(pool_.size()), pool_.data());
}

uint32_t BoxQuerier::issue(const Aabb& box) {
  if (next_ == pool_.size()) {
    const size_t old = pool_.size();
    pool_.resize(old + 64);
    gl_.CreateQueries(GL_SAMPLES_PASSED, 64, pool_.data() + old);
  }
  const uint32_t handle = next_++;
  ++queries_issued_;
  if (near_.size() < pool_.size()) near_.resize(pool_.size());
  const DrawnBox b = box.empty() ? DrawnBox{} : drawn_box(box, box_.eye, box_.reach, box_.pixel_pad);
  near_[handle] = !box.empty() && b.near;
  if (near_[handle]) return handle;  // visible, not drawn
  gl_.BeginQuery(GL_SAMPLES_PASSED, pool_[handle]);
  if (!box.empty()) {
    gl_.ProgramUniform3f(box_.program, min_loc_, b.lo.x, b.lo.y, b.lo.z);
    gl_.ProgramUniform3f(box_.program, max_loc_, b.hi.x, b.hi.y, b.hi.z);
    gl_.DrawArrays(GL_TRIANGLES, 0, 36);
  }
  gl_.EndQuery(GL_SAMPLES_PASSED);
  return handle;
}

uint64_t BoxQuerier::result(uint32_t handle) {
  if (handle >= next_)
    throw std::out_of_range("BoxQuerier: query handle " + std::to_string(handle) +
                            " not issued in this batch (" + std::to_string(next_) + " issued)");
  if (near_[handle]) return box_.pixels;
  GLuint64 samples = 0;
  gl_.GetQueryObjectui64v(pool_[handle], GL_QUERY_RESULT, &samples);
  return samples;
}

bool BoxQuerier::ready(uint32_t handle) const {
  if (handle >= next_) throw std::out_of_range("BoxQuerier: query handle not issued in this batch");
  if (near_[handle]) return true;
  GLuint64 available = 0;
  gl_.GetQueryObjectui64v(pool_[handle], GL_QUERY_RESULT_AVAILABLE, &available);
  return available != 0;
}

void BoxQuerier::reset() { next_ = 0; }

BoxBatchCounter::BoxBatchCounter(GlContext& ctx, bool exact)
    : BoxTester(ctx, link_program(ctx.gl(), kBatchVertex,
                                  std::string("#version 450 core\n") + (exact ? "#define EXACT\n" : "") + kBatchFragment)),
      exact_(exact) {
  first_loc_ = gl_.GetUniformLocation(box_.program, "u_first");
  gl_.CreateBuffers(1, &boxes_buf_);
  gl_.CreateBuffers(1, &counts_buf_);
}

BoxBatchCounter::~BoxBatchCounter() {
  gl_.DeleteBuffers(1, &boxes_buf_);
  gl_.DeleteBuffers(1, &counts_buf_);
}

uint32_t BoxBatchCounter::issue(const Aabb& box) {
  if (drawn_) throw std::logic_error("BoxBatchCounter: issue() after result() in one batch (call reset() first)");
  ++queries_issued_;
  boxes_.push_back(box);
  return uint32_t(boxes_.size() - 1);
}

void BoxBatchCounter::draw() {
  drawn_ = true;
  counts_.assign(boxes_.size(), 0);
  // Buffer slots: the boxes drawn; empty ones none, near ones none (the viewport's pixels, as BoxQuerier).
  slot_.assign(boxes_.size(), ~0u);
  std::vector<glm::vec4> data;
  data.reserve(2 * boxes_.size());
  uint32_t n = 0;
  for (uint32_t i = 0; i < boxes_.size(); ++i) {
    if (boxes_[i].empty()) continue;
    const DrawnBox b = drawn_box(boxes_[i], box_.eye, box_.reach, box_.pixel_pad);
    if (b.near) {
      counts_[i] = exact_ ? box_.pixels : 1;
      continue;
    }
    slot_[i] = n++;
    data.emplace_back(b.lo, 0.0f);
    data.emplace_back(b.hi, 0.0f);
  }
  if (n == 0) return;
  if (n > capacity_) {
    capacity_ = std::max<size_t>(n, 2 * capacity_);
    gl_.NamedBufferData(boxes_buf_, GLsizeiptr(capacity_ * 2 * sizeof(glm::vec4)), nullptr, GL_STREAM_DRAW);
    gl_.NamedBufferData(counts_buf_, GLsizeiptr(capacity_ * sizeof(uint32_t)), nullptr, GL_STREAM_READ);
  }
  gl_.NamedBufferSubData(boxes_buf_, 0, GLsizeiptr(data.size() * sizeof(glm::vec4)), data.data());
  const std::vector<uint32_t> zeros(n, 0);
  gl_.NamedBufferSubData(counts_buf_, 0, GLsizeiptr(n * sizeof(uint32_t)), zeros.data());
  gl_.UseProgram(box_.program);  // BoxQuerier's may be bound (CpuPyramidTests issues both)
  gl_.BindVertexArray(box_.vao);
  gl_.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 2, boxes_buf_);
  gl_.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 3, counts_buf_);
  gl_.ProgramUniform1i(box_.program, first_loc_, 0);
  gl_.DrawArrays(GL_TRIANGLES, 0, GLsizei(36 * n));
  ++draws_;
  gl_.MemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
  std::vector<uint32_t> got(n);
  gl_.GetNamedBufferSubData(counts_buf_, 0, GLsizeiptr(n * sizeof(uint32_t)), got.data());
  for (uint32_t i = 0; i < boxes_.size(); ++i)
    if (slot_[i] != ~0u) counts_[i] = got[slot_[i]];
}

uint64_t BoxBatchCounter::result(uint32_t handle) {
  if (handle >= boxes_.size())
    throw std::out_of_range("BoxBatchCounter: handle " + std::to_string(handle) + " not issued in this batch (" +
                            std::to_string(boxes_.size()) + " issued)");
  if (!drawn_) draw();
  return counts_[handle];
}

void BoxBatchCounter::reset() {
  boxes_.clear();
  drawn_ = false;
}

}  // namespace occ
