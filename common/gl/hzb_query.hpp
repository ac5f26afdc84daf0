// HC's occlusion tests with a GPU depth pyramid in front of the occlusion queries (issue 16).
//
// GpuDepthPyramid: a hierarchical depth pyramid of farthest depths (reverse-Z: the MIN of 2 x 2
// texels), built by a compute shader from the context's depth texture (GlContext::depth_texture)
// and never read back; level 0 is the depth texture itself, levels 1.. live in one R32F texture
// (its mip k-1 holds level k). test() runs a batch of PyramidProbes (common/hzb.hpp: rectangle,
// level and depth bound computed on the CPU) in one compute dispatch and reads back one word per
// probe from a small shader storage buffer. Level contents equal DepthPyramid::build on the same
// depth (min is exact), so the CPU DepthPyramid::occludes is the shader's specification.
//
// HcQuerier: the OcclusionQueries HC uses (switch nodes, cull_overview), by HcTest:
//   queries  every box is a real occlusion query (BoxQuerier), as before;
//   pyramid  each batch's boxes are first tested against the pyramid in one dispatch; only those
//            it cannot prove occluded become real queries (issued together, then read);
//   automatic  the pyramid for batches of at least kAutoMinProbes probe-able boxes, queries for
//            smaller ones (a dispatch and a read-back cost more than a few queries).
// The pyramid only removes queries whose answer would be 0 (hzb.hpp, "Precision"): the results,
// and so the visible sets, are those of `queries`.
//
// Which depth the pyramid holds: begin() starts a frame's tests against a depth buffer drawn
// since the last build (the OR): the pyramid is rebuilt before its first use. depth_added() says
// more depth was drawn into the same buffer within the frame (occluder fusion). Depth only ever
// gets nearer then (GL_GREATER, depth writes on), so a pyramid built before it still proves only
// true occlusion: it stays in use (conservative, it just proves less) and is rebuilt when a batch
// is large enough to be worth it (pyramid: any batch of at least kRebuildMinProbes; automatic: of
// at least kAutoRebuildMinProbes).
// Contracts: the GlContext is current on the calling thread and outlives the querier; nothing
// draws into the depth buffer between begin()/depth_added() and the batch's results but the
// querier itself (its queries write no depth).
#pragma once
#include <cstdint>
#include <memory>
#include <vector>

#include "common/culling.hpp"
#include "common/gl/box_query.hpp"
#include "common/gl/context.hpp"
#include "common/hzb.hpp"

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
  GLuint pyramid_ = 0;              // R32F, levels_ - 1 mip levels (none for a 1 x 1 viewport)
  GLuint probes_buf_ = 0, results_buf_ = 0;
  size_t capacity_ = 0;             // probes the buffers hold
  GLint count_loc_ = -1;
};

class HcQuerier final : public OcclusionQueries {
 public:
  static constexpr size_t kAutoMinProbes = 32;          // automatic: smaller batches are all queries
  static constexpr size_t kRebuildMinProbes = 1;        // pyramid: rebuild a stale pyramid for any batch
  static constexpr size_t kAutoRebuildMinProbes = 256;  // automatic: rebuild a stale one for large batches

  struct Stats {
    uint64_t tests = 0;            // issue() calls: boxes tested
    uint64_t queries = 0;          // real occlusion queries issued
    uint64_t pyramid_tested = 0;   // boxes tested against the pyramid
    uint64_t pyramid_occluded = 0; // of those, proven occluded (no query)
    uint64_t builds = 0;           // pyramid builds
    uint64_t dispatches = 0;       // test dispatches
    uint64_t occluded = 0;         // boxes answered 0 samples (by the pyramid or a query)
  };

  HcQuerier(GlContext& ctx, HcTest test);
  HcTest mode() const { return test_; }

  // A frame's tests against a freshly drawn depth buffer, from `cam`.
  void begin(const Camera& cam);
  // More depth was drawn into this frame's buffer (occluder fusion); restores the query state.
  void depth_added();
  uint32_t issue(const Aabb& box) override;
  uint64_t result(uint32_t handle) override;
  void end_batch() override;
  // Restores colour and depth writes.
  void end() { queries_.end(); }

  const Stats& stats() const { return stats_; }
  BoxQuerier& box_querier() { return queries_; }

 private:
  enum : uint32_t { kPending = ~0u, kZero = ~0u - 1 };
  void resolve();

  HcTest test_;
  GlContext& ctx_;
  BoxQuerier queries_;
  std::unique_ptr<GpuDepthPyramid> pyramid_;  // pyramid / automatic only
  Camera cam_;
  bool built_ = false, stale_ = false, resolved_ = false;
  std::vector<Aabb> boxes_;             // this batch's boxes
  std::vector<PyramidProbe> probes_;    // and their probes
  std::vector<uint32_t> handle_;        // per box: its query handle, kZero (0 samples) or kPending
  std::vector<PyramidProbe> batch_;     // probes sent to the GPU
  std::vector<uint32_t> batch_index_, occluded_;
  Stats stats_;
};

}  // namespace occ
