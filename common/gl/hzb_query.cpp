#include "common/gl/hzb_query.hpp"

#include <algorithm>
#include <bit>
#include <stdexcept>
#include <string>

#include "common/gl/box_query.hpp"
#include "common/gl/shader.hpp"

namespace occ {
namespace {

// Levels k and k + 1 (k >= 1) from level k - 1: each texel the farthest (minimum) of the up to
// 2 x 2 texels below it that exist, as DepthPyramid::build. One invocation per texel of level
// k + 1 computes its up to 2 x 2 texels of level k and their minimum (u_two = 0: level k only).
// FROM_DEPTH: level k - 1 is the depth texture, read with one textureGather per 2 x 2 block (the
// sampler clamps to the edge, so where the last row or column has no partner the gather repeats
// a texel of the same block: the minimum is unchanged); otherwise an R32F image. The sizes are the
// levels' own (the R32F mips are larger: GL halves rounding down, here from a power of two).
const char* const kBuildSource = R"(
layout(local_size_x = 8, local_size_y = 8) in;
#ifdef FROM_DEPTH
layout(binding = 0) uniform sampler2D u_src;
#else
layout(binding = 0, r32f) uniform readonly image2D u_src;
#endif
layout(binding = 1, r32f) uniform writeonly image2D u_dst;
layout(binding = 2, r32f) uniform writeonly image2D u_dst2;
uniform ivec2 u_src_size;
uniform ivec2 u_dst_size;
uniform int u_two;
float reduce(ivec2 s, ivec2 src) {  // the up to 2 x 2 texels of level k - 1 at s
#ifdef FROM_DEPTH
  vec4 g = textureGather(u_src, (vec2(s) + 1.0) / vec2(src));
  return min(min(g.x, g.y), min(g.z, g.w));
#else
  float m = imageLoad(u_src, s).r;
  bool right = s.x + 1 < src.x, up = s.y + 1 < src.y;
  if (right) m = min(m, imageLoad(u_src, s + ivec2(1, 0)).r);
  if (up) m = min(m, imageLoad(u_src, s + ivec2(0, 1)).r);
  if (right && up) m = min(m, imageLoad(u_src, s + ivec2(1, 1)).r);
  return m;
#endif
}
void main() {
  ivec2 p = ivec2(gl_GlobalInvocationID.xy);
  ivec2 src = u_src_size, dst = u_dst_size;
  if (u_two == 0) {
    if (p.x < dst.x && p.y < dst.y) imageStore(u_dst, p, vec4(reduce(2 * p, src)));
    return;
  }
  ivec2 dst2 = (dst + 1) / 2;
  if (p.x >= dst2.x || p.y >= dst2.y) return;
  float m = 1.0;
  for (int j = 0; j < 2; ++j)
    for (int i = 0; i < 2; ++i) {
      ivec2 q = 2 * p + ivec2(i, j);
      if (q.x < dst.x && q.y < dst.y) {
        float v = reduce(2 * q, src);
        imageStore(u_dst, q, vec4(v));
        m = min(m, v);
      }
    }
  imageStore(u_dst2, p, vec4(m));
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
  for (int i = 0; i < 2; ++i) {
    const GLuint prog = i == 0 ? build_from_depth_ : build_from_level_;
    src_size_loc_[i] = gl_.GetUniformLocation(prog, "u_src_size");
    dst_size_loc_[i] = gl_.GetUniformLocation(prog, "u_dst_size");
    two_loc_[i] = gl_.GetUniformLocation(prog, "u_two");
  }
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
  gl_.CreateSamplers(1, &depth_sampler_);  // texel centres of level 0: nearest, clamped
  gl_.SamplerParameteri(depth_sampler_, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
  gl_.SamplerParameteri(depth_sampler_, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
  gl_.SamplerParameteri(depth_sampler_, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
  gl_.SamplerParameteri(depth_sampler_, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
  gl_.SamplerParameteri(depth_sampler_, GL_TEXTURE_COMPARE_MODE, GL_NONE);
}

GpuDepthPyramid::~GpuDepthPyramid() {
  gl_.DeleteSamplers(1, &depth_sampler_);
  gl_.DeleteBuffers(1, &probes_buf_);
  gl_.DeleteBuffers(1, &results_buf_);
  if (pyramid_) gl_.DeleteTextures(1, &pyramid_);
  gl_.DeleteProgram(build_from_depth_);
  gl_.DeleteProgram(build_from_level_);
  gl_.DeleteProgram(test_);
}

void GpuDepthPyramid::build() {
  int w = vp_.width, h = vp_.height;  // level - 1's size
  for (uint32_t level = 1; level < levels_; level += 2) {
    const GLuint prog = level == 1 ? build_from_depth_ : build_from_level_;
    const bool two = level + 1 < levels_;
    const int dw = (w + 1) / 2, dh = (h + 1) / 2;
    gl_.ProgramUniform2i(prog, src_size_loc_[level == 1 ? 0 : 1], w, h);
    gl_.ProgramUniform2i(prog, dst_size_loc_[level == 1 ? 0 : 1], dw, dh);
    gl_.ProgramUniform1i(prog, two_loc_[level == 1 ? 0 : 1], two ? 1 : 0);
    gl_.UseProgram(prog);
    if (level == 1) {
      gl_.BindTextureUnit(0, ctx_.depth_texture());
      gl_.BindSampler(0, depth_sampler_);
    } else {
      gl_.BindImageTexture(0, pyramid_, GLint(level - 2), GL_FALSE, 0, GL_READ_ONLY, GL_R32F);
      gl_.MemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT);  // the level below is written
    }
    gl_.BindImageTexture(1, pyramid_, GLint(level - 1), GL_FALSE, 0, GL_WRITE_ONLY, GL_R32F);
    gl_.BindImageTexture(2, pyramid_, GLint(two ? level : level - 1), GL_FALSE, 0, GL_WRITE_ONLY, GL_R32F);
    const int gw = two ? (dw + 1) / 2 : dw, gh = two ? (dh + 1) / 2 : dh;
    gl_.DispatchCompute(GLuint((gw + 7) / 8), GLuint((gh + 7) / 8), 1);
    w = two ? (dw + 1) / 2 : dw;
    h = two ? (dh + 1) / 2 : dh;
  }
  gl_.BindTextureUnit(0, 0);
  gl_.BindSampler(0, 0);
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

uint64_t probe_pixels(const PyramidProbe& p) {
  return (uint64_t(p.x1 - p.x0 + 1) * uint64_t(p.y1 - p.y0 + 1)) << (2 * p.level);
}

uint32_t PyramidBatch::add(const Aabb& box, bool cheap_only, const Camera& cam, Viewport vp, int span) {
  if (resolved) throw std::logic_error("depth pyramid tests: issue() after result() in one batch (call end_batch() first)");
  boxes.push_back(box);
  cheap.push_back(cheap_only ? 1 : 0);
  probes.push_back(pyramid_probe(box, cam, vp, BoxQuerier::kRelativePad, span));
  return uint32_t(boxes.size() - 1);
}

void PyramidBatch::resolve_start() {
  resolved = true;
  answer.assign(boxes.size(), kPending);
  sent.clear();
  sent_index.clear();
  for (size_t i = 0; i < boxes.size(); ++i) {
    if (probes[i].kind == PyramidProbe::Kind::no_samples) {
      answer[i] = kZero;
    } else if (probes[i].kind == PyramidProbe::Kind::probe) {
      sent.push_back(probes[i]);
      sent_index.push_back(uint32_t(i));
    }
  }
}

uint64_t PyramidBatch::take_occluded(uint64_t& pixels) {
  uint64_t n = 0;
  for (size_t j = 0; j < sent.size(); ++j)
    if (occluded[j]) {
      answer[sent_index[j]] = kZero;
      ++n;
      pixels += probe_pixels(sent[j]);
    }
  return n;
}

uint64_t PyramidBatch::assume_cheap() {
  uint64_t n = 0;
  for (size_t i = 0; i < boxes.size(); ++i)
    if (answer[i] == kPending && cheap[i]) {
      answer[i] = kAssumed;
      ++n;
    }
  return n;
}

uint32_t PyramidBatch::at(uint32_t handle) const {
  if (handle >= boxes.size())
    throw std::out_of_range("depth pyramid tests: handle " + std::to_string(handle) + " not issued in this batch (" +
                            std::to_string(boxes.size()) + " issued)");
  return answer[handle];
}

void PyramidBatch::clear() {
  boxes.clear();
  cheap.clear();
  probes.clear();
  resolved = false;
}

}  // namespace occ
