#include "common/gl/hzb_query.hpp"

#include <algorithm>
#include <bit>
#include <stdexcept>
#include <string>

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

HcQuerier::Policy HcQuerier::policy(HcStrategy test) {
  Policy p;
  if (test == HcStrategy::cpu_pyramid) p.min_decided_screens = 0.25;
  return p;
}

namespace {
// The pixels a probe's rectangle covers (at level 0).
uint64_t probe_pixels(const PyramidProbe& p) {
  return (uint64_t(p.x1 - p.x0 + 1) * uint64_t(p.y1 - p.y0 + 1)) << (2 * p.level);
}
}  // namespace

HcQuerier::HcQuerier(GlContext& ctx, HcStrategy test, bool sample_counts, const Policy& policy)
    : test_(test),
      sample_counts_(sample_counts),
      policy_(policy),
      ctx_(ctx),
      queries_(ctx) {
  if (test_ == HcStrategy::cpu_pyramid) {
    cpu_pyramid_ = std::make_unique<DepthPyramid>();
    counter_ = std::make_unique<BoxBatchCounter>(ctx, sample_counts);
  }
  if (test_ == HcStrategy::pyramid) pyramid_ = std::make_unique<GpuDepthPyramid>(ctx);
}

void HcQuerier::begin(const Camera& cam) {
  // cpu_pyramid: the frame just ended decided boxes covering that many pixels; frames whose
  // pyramid would not pay do without it, with a frame with the pyramid every kRetryFrames to look again.
  if (built_) proven_avg_ = proven_avg_ < 0 ? double(proven_frame_) : 0.5 * proven_avg_ + 0.5 * double(proven_frame_);
  const double need = cpu_pyramid_ ? policy_.min_decided_screens * ctx_.width() * ctx_.height() : 0.0;
  use_pyramid_ = (pyramid_ || cpu_pyramid_) &&
                 (need == 0 || proven_avg_ < 0 || proven_avg_ >= need || ++frames_off_ % kRetryFrames == 0);
  if (use_pyramid_) frames_off_ = 0;
  proven_frame_ = 0;
  cam_ = cam;
  built_ = stale_ = false;
  clear_dirty();
  q_begin(cam);
}

void HcQuerier::depth_added(std::span<const Aabb> drawn) {
  stale_ = built_;
  const int w = ctx_.width(), h = ctx_.height();
  if (drawn.empty()) dirty_.add({0, 0, w - 1, h - 1});
  for (const Aabb& box : drawn) dirty_.add_box(box, cam_, {w, h});
  q_begin(cam_);
}

// cpu_pyramid: level 0 read back and the levels built once a frame; after occluder fusion drew,
// the drawn rectangle read again and the levels above it rebuilt, when it is no larger than the
// rectangles of the batch's boxes (both cost about the same per pixel; otherwise the boxes go to
// the GPU against a pyramid that is stale there: still conservative for occlusion).
void HcQuerier::cpu_refresh() {
  const int w = ctx_.width(), h = ctx_.height();
  if (!built_) {
    ctx_.read_depth(cpu_pyramid_->level0(w, h));
    cpu_pyramid_->build_levels();
    built_ = true;
    stale_ = false;
    clear_dirty();
    ++stats_.builds;
    return;
  }
  if (dirty_.empty()) return;
  double boxes = 0;
  for (const PyramidProbe& p : probes_)
    boxes += p.kind == PyramidProbe::Kind::probe ? double(probe_pixels(p)) : p.kind == PyramidProbe::Kind::query ? double(w) * h : 0.0;
  if (dirty_.pixels() > boxes) return;
  const PixelRect& d = dirty_;
  ctx_.read_depth(d.x0, d.y0, d.x1 - d.x0 + 1, d.y1 - d.y0 + 1, cpu_pyramid_->level0(w, h));
  cpu_pyramid_->build_levels(d.x0, d.y0, d.x1, d.y1);
  stale_ = false;
  clear_dirty();
  ++stats_.refreshes;
}

uint32_t HcQuerier::issue(const Aabb& box) {
  ++stats_.tests;
  if (!use_pyramid_) return q_issue(box);
  if (resolved_) throw std::logic_error("HcQuerier: issue() after result() in one batch (call end_batch() first)");
  boxes_.push_back(box);
  cheap_.push_back(0);
  probes_.push_back(pyramid_probe(box, cam_, {ctx_.width(), ctx_.height()}, BoxQuerier::kRelativePad, policy_.span));
  return uint32_t(boxes_.size() - 1);
}

uint32_t HcQuerier::issue_cheap(const Aabb& box) {
  if (!use_pyramid_) throw std::logic_error("HcQuerier: issue_cheap() in a frame without the pyramid (cheap_tests())");
  const uint32_t handle = issue(box);
  cheap_.back() = 1;
  ++stats_.cheap;
  return handle;
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
  if (cpu_pyramid_) cpu_refresh();
  if (!batch_.empty()) {
    if (!cpu_pyramid_ && (!built_ || (stale_ && batch_.size() >= policy_.rebuild_min_probes))) {
      pyramid_->build();
      built_ = true;
      stale_ = false;
      ++stats_.builds;
    }
    if (cpu_pyramid_) {
      occluded_.resize(batch_.size());
      for (size_t j = 0; j < batch_.size(); ++j) occluded_[j] = cpu_pyramid_->occludes(batch_[j]);
    } else {
      pyramid_->test(batch_, occluded_);
      ++stats_.dispatches;
    }
    stats_.pyramid_tested += batch_.size();
    for (size_t j = 0; j < batch_.size(); ++j)
      if (occluded_[j]) {
        handle_[batch_index_[j]] = kZero;
        ++stats_.pyramid_occluded;
        const uint64_t pixels = probe_pixels(batch_[j]);
        stats_.pyramid_pixels += pixels;
        proven_frame_ += cpu_pyramid_ ? pixels : 1;
      }
    if (!cpu_pyramid_) q_begin(cam_);  // the dispatches changed the program
  }
  // Skipped by adaptive queries (issue_cheap) and not proven occluded: assumed visible.
  for (size_t i = 0; i < boxes_.size(); ++i)
    if (handle_[i] == kPending && cheap_[i]) {
      handle_[i] = kAssumed;
      ++stats_.assumed;
    }
  // cpu_pyramid without sample counts also proves boxes that show, from level 0, which must be
  // the current depth under the box: not where occluder fusion drew since it was read.
  if (cpu_pyramid_ && !sample_counts_)
    for (size_t i = 0; i < boxes_.size(); ++i)
      if (handle_[i] == kPending && clean_under(boxes_[i]) && cpu_pyramid_->shows(boxes_[i], cam_)) {
        handle_[i] = kShows;
        ++stats_.shown;
        proven_frame_ += probes_[i].kind == PyramidProbe::Kind::probe ? probe_pixels(probes_[i])
                                                                       : uint64_t(ctx_.width()) * uint64_t(ctx_.height());
      }
  for (size_t i = 0; i < boxes_.size(); ++i)
    if (handle_[i] == kPending) {
      handle_[i] = q_issue(boxes_[i]);
    }
}

void HcQuerier::clear_dirty() { dirty_.clear(); }

bool HcQuerier::clean_under(const Aabb& box) const {
  return dirty_.empty() || !dirty_.touches(box_footprint(box, cam_, {ctx_.width(), ctx_.height()}));
}

uint64_t HcQuerier::result(uint32_t handle) {
  uint64_t samples = 0;
  if (!use_pyramid_) {
    samples = q_result(handle);
  } else {
    if (handle >= boxes_.size())
      throw std::out_of_range("HcQuerier: handle " + std::to_string(handle) + " not issued in this batch (" +
                              std::to_string(boxes_.size()) + " issued)");
    if (!resolved_) resolve();
    const uint32_t h = handle_[handle];
    samples = h == kZero ? 0 : h == kShows || h == kAssumed ? 1 : q_result(h);
  }
  stats_.occluded += samples == 0;
  return samples;
}

void HcQuerier::q_begin(const Camera& cam) {
  if (counter_) counter_->begin(cam);
  queries_.begin(cam);  // last: its program is bound for issue()
}
uint32_t HcQuerier::q_issue(const Aabb& box) {
  if (counter_) {
    // Boxes covering many pixels (or possibly the whole view) are cheaper as queries: every
    // fragment of the batch draw that passes runs the counting shader.
    const BoxFootprint fp = box_footprint(box, cam_, {ctx_.width(), ctx_.height()});
    const bool big = fp.kind == BoxFootprint::Kind::NearPlane ||
                     (fp.kind == BoxFootprint::Kind::OnScreen &&
                      double(fp.x1 - fp.x0 + 1) * double(fp.y1 - fp.y0 + 1) > double(policy_.batch_max_pixels));
    if (!big) {
      ++stats_.batched;
      return counter_->issue(box);
    }
  }
  ++stats_.queries;
  return queries_.issue(box) | kQueryBit;
}

uint64_t HcQuerier::q_result(uint32_t h) {
  if (!counter_) return queries_.result(h & ~kQueryBit);
  if (h & kQueryBit) {
    if (!counter_->drawn()) counter_->draw();  // the batch draw first: one flush for both
    return queries_.result(h & ~kQueryBit);
  }
  return counter_->result(h);
}

void HcQuerier::end_batch() {
  queries_.reset();
  if (counter_) {
    if (counter_->drawn()) queries_.begin(cam_);  // the batch draw bound its own program
    counter_->reset();
    stats_.draws = counter_->draws();
  }
  boxes_.clear();
  cheap_.clear();
  probes_.clear();
  resolved_ = false;
}

}  // namespace occ
