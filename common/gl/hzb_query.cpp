#include "common/gl/hzb_query.hpp"

#include <algorithm>
#include <bit>
#include <stdexcept>
#include <string>

#include "common/gl/shader.hpp"

namespace occ {
namespace {

// Level k (>= 1) from level k - 1: each texel the farthest (minimum) of the up to 2 x 2 texels
// below it that exist (odd sizes: the last row / column has fewer), as DepthPyramid::build.
// FROM_DEPTH: level 0 is the depth texture (texelFetch); otherwise an R32F image. The sizes are
// the levels' own (the R32F mips are larger: GL halves rounding down, from a power of two here).
const char* const kBuildSource = R"(
layout(local_size_x = 8, local_size_y = 8) in;
#ifdef FROM_DEPTH
layout(binding = 0) uniform sampler2D u_src;
#define SRC(p) texelFetch(u_src, p, 0).r
#else
layout(binding = 0, r32f) uniform readonly image2D u_src;
#define SRC(p) imageLoad(u_src, p).r
#endif
layout(binding = 1, r32f) uniform writeonly image2D u_dst;
uniform ivec2 u_src_size;
uniform ivec2 u_dst_size;
void main() {
  ivec2 p = ivec2(gl_GlobalInvocationID.xy);
  ivec2 src = u_src_size, dst = u_dst_size;
  if (p.x >= dst.x || p.y >= dst.y) return;
  ivec2 s = 2 * p;
  float m = SRC(s);
  bool right = s.x + 1 < src.x, up = s.y + 1 < src.y;
  if (right) m = min(m, SRC(s + ivec2(1, 0)));
  if (up) m = min(m, SRC(s + ivec2(0, 1)));
  if (right && up) m = min(m, SRC(s + ivec2(1, 1)));
  imageStore(u_dst, p, vec4(m));
}
)";

// One probe per invocation: occluded when its depth bound is strictly farther (smaller) than every
// texel of its rectangle (at most 2 x 2) at its level (DepthPyramid::occludes).
const char* const kTestSource = R"(#version 450 core
layout(local_size_x = 64) in;
struct Probe { ivec4 rect; uint level; float depth; uint pad0; uint pad1; };
layout(std430, binding = 0) readonly buffer Probes { Probe probes[]; };
layout(std430, binding = 1) writeonly buffer Results { uint occluded[]; };
layout(binding = 0) uniform sampler2D u_depth;    // level 0
layout(binding = 1) uniform sampler2D u_pyramid;  // level k at mip k - 1
uniform int u_count;
void main() {
  uint i = gl_GlobalInvocationID.x;
  if (i >= uint(u_count)) return;
  Probe p = probes[i];
  bool occ = true;
  for (int y = p.rect.y; y <= p.rect.w; ++y)
    for (int x = p.rect.x; x <= p.rect.z; ++x) {
      float d = p.level == 0u ? texelFetch(u_depth, ivec2(x, y), 0).r
                              : texelFetch(u_pyramid, ivec2(x, y), int(p.level) - 1).r;
      occ = occ && p.depth < d;
    }
  occluded[i] = occ ? 1u : 0u;
}
)";

struct GpuProbe {  // std430 layout of Probe
  int32_t x0, y0, x1, y1;
  uint32_t level;
  float depth;
  uint32_t pad0 = 0, pad1 = 0;
};
static_assert(sizeof(GpuProbe) == 32);

}  // namespace

GpuDepthPyramid::GpuDepthPyramid(GlContext& ctx)
    : gl_(ctx.gl()), ctx_(ctx), vp_{ctx.width(), ctx.height()}, levels_(pyramid_level_count(vp_)) {
  build_from_depth_ = link_compute_program(gl_, std::string("#version 450 core\n#define FROM_DEPTH\n") + kBuildSource);
  build_from_level_ = link_compute_program(gl_, std::string("#version 450 core\n") + kBuildSource);
  test_ = link_compute_program(gl_, kTestSource);
  count_loc_ = gl_.GetUniformLocation(test_, "u_count");
  if (levels_ > 1) {
    // Level k is ceil(size / 2^k); GL's mip k of a base B is floor(B / 2^k). From a power-of-two
    // base at least level 1's size, every mip holds its level (and has enough mips).
    gl_.CreateTextures(GL_TEXTURE_2D, 1, &pyramid_);
    gl_.TextureStorage2D(pyramid_, GLsizei(levels_ - 1), GL_R32F, GLsizei(std::bit_ceil(unsigned(vp_.width + 1) / 2)),
                         GLsizei(std::bit_ceil(unsigned(vp_.height + 1) / 2)));
    gl_.TextureParameteri(pyramid_, GL_TEXTURE_MIN_FILTER, GL_NEAREST_MIPMAP_NEAREST);
    gl_.TextureParameteri(pyramid_, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
  }
  gl_.CreateBuffers(1, &probes_buf_);
  gl_.CreateBuffers(1, &results_buf_);
}

GpuDepthPyramid::~GpuDepthPyramid() {
  gl_.DeleteBuffers(1, &probes_buf_);
  gl_.DeleteBuffers(1, &results_buf_);
  if (pyramid_) gl_.DeleteTextures(1, &pyramid_);
  gl_.DeleteProgram(build_from_depth_);
  gl_.DeleteProgram(build_from_level_);
  gl_.DeleteProgram(test_);
}

void GpuDepthPyramid::build() {
  int w = vp_.width, h = vp_.height;
  for (uint32_t level = 1; level < levels_; ++level) {
    const GLuint prog = level == 1 ? build_from_depth_ : build_from_level_;
    gl_.ProgramUniform2i(prog, gl_.GetUniformLocation(prog, "u_src_size"), w, h);
    w = (w + 1) / 2;
    h = (h + 1) / 2;
    gl_.ProgramUniform2i(prog, gl_.GetUniformLocation(prog, "u_dst_size"), w, h);
    if (level == 1) {
      gl_.UseProgram(build_from_depth_);
      gl_.BindTextureUnit(0, ctx_.depth_texture());
    } else {
      gl_.UseProgram(build_from_level_);
      gl_.BindImageTexture(0, pyramid_, GLint(level - 2), GL_FALSE, 0, GL_READ_ONLY, GL_R32F);
      gl_.MemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT);  // the level below is written
    }
    gl_.BindImageTexture(1, pyramid_, GLint(level - 1), GL_FALSE, 0, GL_WRITE_ONLY, GL_R32F);
    gl_.DispatchCompute(GLuint((w + 7) / 8), GLuint((h + 7) / 8), 1);
  }
  gl_.BindTextureUnit(0, 0);
  gl_.MemoryBarrier(GL_TEXTURE_FETCH_BARRIER_BIT | GL_SHADER_IMAGE_ACCESS_BARRIER_BIT);
}

void GpuDepthPyramid::test(const std::vector<PyramidProbe>& probes, std::vector<uint32_t>& occluded) {
  occluded.assign(probes.size(), 0);
  if (probes.empty()) return;
  if (probes.size() > capacity_) {
    capacity_ = std::max(probes.size(), 2 * capacity_);
    gl_.NamedBufferData(probes_buf_, GLsizeiptr(capacity_ * sizeof(GpuProbe)), nullptr, GL_STREAM_DRAW);
    gl_.NamedBufferData(results_buf_, GLsizeiptr(capacity_ * sizeof(uint32_t)), nullptr, GL_STREAM_READ);
  }
  std::vector<GpuProbe> gpu(probes.size());
  for (size_t i = 0; i < probes.size(); ++i) {
    const PyramidProbe& p = probes[i];
    if (p.kind != PyramidProbe::Kind::probe || p.level >= levels_)
      throw std::logic_error("GpuDepthPyramid::test: probe " + std::to_string(i) + " is not a probe of this pyramid");
    gpu[i] = {p.x0, p.y0, p.x1, p.y1, p.level, p.depth};
  }
  gl_.NamedBufferSubData(probes_buf_, 0, GLsizeiptr(gpu.size() * sizeof(GpuProbe)), gpu.data());
  gl_.UseProgram(test_);
  gl_.ProgramUniform1i(test_, count_loc_, GLint(probes.size()));
  gl_.BindTextureUnit(0, ctx_.depth_texture());
  gl_.BindTextureUnit(1, pyramid_);
  gl_.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, probes_buf_);
  gl_.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, results_buf_);
  gl_.DispatchCompute(GLuint((probes.size() + 63) / 64), 1, 1);
  gl_.MemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
  gl_.GetNamedBufferSubData(results_buf_, 0, GLsizeiptr(probes.size() * sizeof(uint32_t)), occluded.data());
  gl_.BindTextureUnit(0, 0);
  gl_.BindTextureUnit(1, 0);
}

std::vector<float> GpuDepthPyramid::read_level(uint32_t level) const {
  if (level == 0 || level >= levels_) throw std::out_of_range("GpuDepthPyramid::read_level: no level " + std::to_string(level));
  int w = vp_.width, h = vp_.height;
  for (uint32_t l = 0; l < level; ++l) w = (w + 1) / 2, h = (h + 1) / 2;
  int mw = int(std::bit_ceil(unsigned(vp_.width + 1) / 2)), mh = int(std::bit_ceil(unsigned(vp_.height + 1) / 2));
  for (uint32_t l = 1; l < level; ++l) mw = std::max(1, mw / 2), mh = std::max(1, mh / 2);
  std::vector<float> mip(size_t(mw) * mh), out(size_t(w) * h);
  gl_.MemoryBarrier(GL_TEXTURE_UPDATE_BARRIER_BIT);
  gl_.GetTextureImage(pyramid_, GLint(level - 1), GL_RED, GL_FLOAT, GLsizei(mip.size() * sizeof(float)), mip.data());
  for (int y = 0; y < h; ++y)
    std::copy_n(mip.begin() + ptrdiff_t(y) * mw, w, out.begin() + ptrdiff_t(y) * w);
  return out;
}

HcQuerier::HcQuerier(GlContext& ctx, HcTest test) : test_(test), ctx_(ctx), queries_(ctx) {
  if (test_ != HcTest::queries) pyramid_ = std::make_unique<GpuDepthPyramid>(ctx);
}

void HcQuerier::begin(const Camera& cam) {
  cam_ = cam;
  built_ = stale_ = false;
  queries_.begin(cam);
}

void HcQuerier::depth_added() {
  stale_ = built_;
  queries_.begin(cam_);
}

uint32_t HcQuerier::issue(const Aabb& box) {
  ++stats_.tests;
  if (test_ == HcTest::queries) {
    ++stats_.queries;
    return queries_.issue(box);
  }
  if (resolved_) throw std::logic_error("HcQuerier: issue() after result() in one batch (call end_batch() first)");
  boxes_.push_back(box);
  probes_.push_back(pyramid_probe(box, cam_, pyramid_->viewport(), BoxQuerier::kRelativePad));
  return uint32_t(boxes_.size() - 1);
}

void HcQuerier::resolve() {
  resolved_ = true;
  handle_.assign(boxes_.size(), kPending);
  batch_.clear();
  batch_index_.clear();
  for (size_t i = 0; i < boxes_.size(); ++i) {
    if (probes_[i].kind == PyramidProbe::Kind::no_samples) {
      handle_[i] = kZero;
    } else if (probes_[i].kind == PyramidProbe::Kind::probe) {
      batch_.push_back(probes_[i]);
      batch_index_.push_back(uint32_t(i));
    }
  }
  const bool automatic = test_ == HcTest::automatic;
  if (!batch_.empty() && (!automatic || batch_.size() >= kAutoMinProbes)) {
    if (!built_ || (stale_ && batch_.size() >= (automatic ? kAutoRebuildMinProbes : kRebuildMinProbes))) {
      pyramid_->build();
      built_ = true;
      stale_ = false;
      ++stats_.builds;
    }
    pyramid_->test(batch_, occluded_);
    ++stats_.dispatches;
    stats_.pyramid_tested += batch_.size();
    for (size_t j = 0; j < batch_.size(); ++j)
      if (occluded_[j]) {
        handle_[batch_index_[j]] = kZero;
        ++stats_.pyramid_occluded;
      }
    queries_.begin(cam_);  // the dispatches changed the program
  }
  for (size_t i = 0; i < boxes_.size(); ++i)
    if (handle_[i] == kPending) {
      handle_[i] = queries_.issue(boxes_[i]);
      ++stats_.queries;
    }
}

uint64_t HcQuerier::result(uint32_t handle) {
  uint64_t samples = 0;
  if (test_ == HcTest::queries) {
    samples = queries_.result(handle);
  } else {
    if (handle >= boxes_.size())
      throw std::out_of_range("HcQuerier: handle " + std::to_string(handle) + " not issued in this batch (" +
                              std::to_string(boxes_.size()) + " issued)");
    if (!resolved_) resolve();
    samples = handle_[handle] == kZero ? 0 : queries_.result(handle_[handle]);
  }
  stats_.occluded += samples == 0;
  return samples;
}

void HcQuerier::end_batch() {
  queries_.reset();
  boxes_.clear();
  probes_.clear();
  resolved_ = false;
}

}  // namespace occ
