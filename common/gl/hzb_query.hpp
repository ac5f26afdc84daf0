// HC's occlusion tests against GL's depth, the shared parts: the GPU depth pyramid, the interface
// of the tests a GL back end runs (GlDepthTests: one class a strategy, gl_query_tests.hpp,
// gl_pyramid_tests.hpp, gl_cpu_pyramid_tests.hpp), and the batch of boxes the two pyramid
// strategies keep (PyramidBatch).
//
// GpuDepthPyramid: a hierarchical depth pyramid of farthest depths (reverse-Z: the MIN of 2 x 2
// texels), built by a compute shader from the context's depth texture (GlContext::depth_texture),
// two levels per dispatch, and never read back; level 0 is the depth texture itself, levels 1..
// live in one R32F texture (its mip k-1 holds level k). test() runs a batch of PyramidProbes
// (common/cull/hzb.hpp: rectangle, level and depth bound computed on the CPU) in one compute
// dispatch and reads back one word per probe from a small shader storage buffer. Level contents
// equal DepthPyramid::build on the same depth (min is exact), so the CPU DepthPyramid::occludes
// is the shader's specification.
//
// A pyramid only removes queries whose answer would be 0 (hzb.hpp, "Precision"): every strategy
// finds the visible sets of plain queries.
#pragma once
#include <cstdint>
#include <span>
#include <vector>

#include "common/cull/culling.hpp"
#include "common/cull/hzb.hpp"
#include "common/cull/occlusion_backend.hpp"
#include "common/gl/context.hpp"

namespace occ {

class GpuDepthPyramid {
 public:
  explicit GpuDepthPyramid(GlContext& ctx);
  ~GpuDepthPyramid();
  GpuDepthPyramid(const GpuDepthPyramid&) = delete;
  GpuDepthPyramid& operator=(const GpuDepthPyramid&) = delete;

  Viewport viewport() const { return vp_; }
  uint32_t level_count() const { return levels_; }
  // Rebuilds levels 1.. from the depth texture (one dispatch per level, nothing read back).
  void build();
  // occluded[i] = 1 when probes[i] (Kind::probe) is proven occluded, 0 otherwise. One dispatch.
  void test(const std::vector<PyramidProbe>& probes, std::vector<uint32_t>& occluded);
  // Level `level` (>= 1) read back, row 0 at the bottom (tests only).
  std::vector<float> read_level(uint32_t level) const;

 private:
  const GlApi& gl_;
  GlContext& ctx_;
  Viewport vp_;
  uint32_t levels_ = 1;
  GLuint build_from_depth_ = 0, build_from_level_ = 0, test_ = 0;
  GLuint depth_sampler_ = 0;
  GLuint pyramid_ = 0;              // R32F, levels_ - 1 mip levels (none for a 1 x 1 viewport)
  GLuint probes_buf_ = 0, results_buf_ = 0;
  size_t capacity_ = 0;             // probes the buffers hold
  GLint count_loc_ = -1, src_size_loc_[2] = {-1, -1}, dst_size_loc_[2] = {-1, -1}, two_loc_[2] = {-1, -1};
};

// The tests of a GL back end (gl_depth_backend.hpp), against the context's depth buffer.
// Contracts: the GlContext is current on the calling thread and outlives the tests; nothing
// draws into the depth buffer between begin()/depth_added() and the batch's results but the
// tests themselves (their queries write no depth).
class GlDepthTests : public OcclusionQueries {
 public:
  virtual const char* name() const = 0;  // its --backend word
  // A frame's tests against a freshly drawn depth buffer, from `cam`.
  virtual void begin(const Camera& cam) = 0;
  // More depth was drawn into this frame's buffer (occluder fusion), inside the world boxes
  // `drawn` (empty: anything, anywhere); restores the query state.
  virtual void depth_added(std::span<const Aabb> drawn) = 0;
  // Restores colour and depth writes.
  virtual void end() = 0;
  virtual OcclusionCounts counts() const = 0;
};

// One batch of boxes in front of a depth pyramid: each box, whether issue_cheap() issued it (then
// only the pyramid tests it: not proven occluded, it is assumed visible), its probe, and once
// resolved its answer: kZero, kShows, kAssumed, or a handle of the strategy's own.
struct PyramidBatch {
  enum : uint32_t { kPending = ~0u, kZero = ~0u - 1, kShows = ~0u - 2, kAssumed = ~0u - 3 };
  std::vector<Aabb> boxes;
  std::vector<uint8_t> cheap;
  std::vector<PyramidProbe> probes;
  std::vector<uint32_t> answer;  // per box, after resolve_start()
  std::vector<PyramidProbe> sent;  // the probes of Kind::probe, for the pyramid
  std::vector<uint32_t> sent_index, occluded;  // their boxes; the pyramid's answers
  bool resolved = false;

  // Adds `box` (its probe for `vp`, rectangles of at most span x span texels); returns its handle.
  uint32_t add(const Aabb& box, bool cheap_only, const Camera& cam, Viewport vp, int span);
  // Starts resolving: boxes with no samples answer kZero, probes go to `sent`.
  void resolve_start();
  // The pyramid's answers are in `occluded`: those boxes answer kZero. Returns how many, and adds
  // the pixels of their rectangles to `pixels`.
  uint64_t take_occluded(uint64_t& pixels);
  // Boxes issue_cheap() issued and not proven occluded answer kAssumed. Returns how many.
  uint64_t assume_cheap();
  // The answer of `handle` (throws where it was not issued in this batch).
  uint32_t at(uint32_t handle) const;
  void clear();
};

// The pixels a probe's rectangle covers (at level 0).
uint64_t probe_pixels(const PyramidProbe& p);

}  // namespace occ
