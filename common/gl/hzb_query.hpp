// HC's occlusion tests against GL's depth: occlusion queries, a GPU depth pyramid in front of them, or a
// CPU depth pyramid read back once a frame.
//
// GpuDepthPyramid: a hierarchical depth pyramid of farthest depths (reverse-Z: the MIN of 2 x 2
// texels), built by a compute shader from the context's depth texture (GlContext::depth_texture),
// two levels per dispatch, and never read back; level 0 is the depth texture itself, levels 1.. live in one R32F texture
// (its mip k-1 holds level k). test() runs a batch of PyramidProbes (common/cull/hzb.hpp: rectangle,
// level and depth bound computed on the CPU) in one compute dispatch and reads back one word per
// probe from a small shader storage buffer. Level contents equal DepthPyramid::build on the same
// depth (min is exact), so the CPU DepthPyramid::occludes is the shader's specification.
//
// HcQuerier: the OcclusionQueries of the GL back ends (gl_depth_backend.hpp), by HcStrategy:
//   queries      every box is a real occlusion query (BoxQuerier): what a hardware GPU would choose;
//   pyramid      each batch's boxes are first tested against the GPU pyramid in one dispatch; only
//                those it cannot prove occluded become real queries (issued together, then read);
//                nothing is read back but one word per probe;
//   cpu_pyramid  HC's depth read back once a frame (glReadPixels)
//                into a DepthPyramid (common/cull/hzb) that proves boxes occluded
//                (DepthPyramid::occludes) and, without sample counts and until occluder fusion
//                draws more, boxes that show (DepthPyramid::shows: answered 1 with no test); the
//                rest are counted by one draw per batch (BoxBatchCounter, no query objects), except
//                those covering more than Policy::batch_max_pixels pixels or within reach of the
//                near plane, which stay queries (the counting shader runs for every passing
//                fragment). Frames whose pyramid decides boxes covering less than
//                Policy::min_decided_screens viewports (a running average) do without it,
//                retrying every kRetryFrames.
// The pyramid only removes queries whose answer would be 0 (hzb.hpp, "Precision"), a box shown
// on the CPU has a sample its query would count, and the batch draw counts the same samples:
// the results, and so the visible sets, are those of `queries` (without `sample_counts` a
// batch-counted or shown box answers 1 for any number of samples).
//
// Which depth the pyramid holds: begin() starts a frame's tests against a depth buffer drawn
// since the last build (the OR): the pyramid is built before its first use in the frame.
// depth_added() says more depth was drawn into the same buffer within the frame (occluder
// fusion). Depth only ever gets nearer then (GL_GREATER, depth writes on), so the pyramid built
// before it still proves only true occlusion: it stays in use (conservative; it just proves a
// little less) and is rebuilt only for batches of at least Policy::rebuild_min_probes probes.
// Contracts: the GlContext is current on the calling thread and outlives the querier; nothing
// draws into the depth buffer between begin()/depth_added() and the batch's results but the
// querier itself (its queries write no depth).
#pragma once
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "common/cull/culling.hpp"
#include "common/gl/box_query.hpp"
#include "common/gl/context.hpp"
#include "common/cull/hzb.hpp"

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

// How HcQuerier tests a box (the GL back ends, gl_depth_backend.hpp).
enum class HcStrategy { queries, pyramid, cpu_pyramid };

class HcQuerier final : public OcclusionQueries {
 public:
  // When the pyramid is used, and how it tests (defaults per HcStrategy: policy()).
  struct Policy {
    size_t rebuild_min_probes = 256;   // pyramid: rebuild a stale pyramid (depth_added) for batches this large
    // cpu_pyramid, > 0: frames whose pyramid decides (proves occluded or showing) boxes whose
    // rectangles cover fewer pixels than this many viewports (average) do without it (batch).
    double min_decided_screens = 0;
    // Probe rectangles span at most span x span texels (hzb.hpp).
    int span = 16;
    // cpu_pyramid: boxes whose screen rectangle covers more pixels are queries (with the eye or the near
    // plane in reach: always), smaller ones are counted by the batch draw.
    double batch_max_pixels = 16384;
  };
  static constexpr uint32_t kRetryFrames = 8;
  static Policy policy(HcStrategy test);

  struct Stats {
    uint64_t tests = 0;            // issue() calls: boxes tested
    uint64_t queries = 0;          // real occlusion queries issued (query objects)
    uint64_t batched = 0;          // cpu_pyramid: boxes counted by batch draws instead
    uint64_t draws = 0;            // batch draws
    uint64_t pyramid_tested = 0;   // boxes tested against the pyramid
    uint64_t pyramid_occluded = 0; // of those, proven occluded (no query)
    uint64_t builds = 0;           // pyramid builds
    uint64_t refreshes = 0;        // cpu_pyramid: partial read-backs and rebuilds after occluder fusion
    uint64_t dispatches = 0;       // test dispatches
    uint64_t occluded = 0;         // boxes answered 0 samples (by the pyramid or a query)
    uint64_t pyramid_pixels = 0;   // pixels of the rectangles of the boxes the pyramid proved
    uint64_t shown = 0;            // cpu_pyramid: boxes proven to show (DepthPyramid::shows), no query
    uint64_t cheap = 0;            // of the tests, issue_cheap() ones (the pyramid only)
    uint64_t assumed = 0;          // of those, not proven occluded: answered 1, nothing tested further
  };

  // `sample_counts`: result() must be the number of samples (visible-pixel LOD), not just > 0.
  HcQuerier(GlContext& ctx, HcStrategy test, bool sample_counts = true) : HcQuerier(ctx, test, sample_counts, policy(test)) {}
  HcQuerier(GlContext& ctx, HcStrategy test, bool sample_counts, const Policy& policy);
  HcStrategy mode() const { return test_; }

  // A frame's tests against a freshly drawn depth buffer, from `cam`.
  void begin(const Camera& cam);
  // More depth was drawn into this frame's buffer (occluder fusion); restores the query state.
  // `drawn`: the world boxes of what was drawn (cpu_pyramid then refreshes only their screen
  // rectangles); empty: anything, anywhere.
  void depth_added(std::span<const Aabb> drawn = {});
  uint32_t issue(const Aabb& box) override;
  // The pyramid's test alone (frames that use it): boxes it cannot prove occluded answer 1.
  bool cheap_tests() const override { return use_pyramid_; }
  uint32_t issue_cheap(const Aabb& box) override;
  uint64_t result(uint32_t handle) override;
  void end_batch() override;
  // Restores colour and depth writes.
  void end() { queries_.end(); }

  const Stats& stats() const { return stats_; }
  BoxQuerier& box_querier() { return queries_; }

 private:
  enum : uint32_t { kPending = ~0u, kZero = ~0u - 1, kShows = ~0u - 2, kAssumed = ~0u - 3, kQueryBit = 1u << 31 };
  void resolve();
  void q_begin(const Camera& cam);
  uint32_t q_issue(const Aabb& box);
  uint64_t q_result(uint32_t h);

  HcStrategy test_;
  bool sample_counts_;
  Policy policy_;
  GlContext& ctx_;
  BoxQuerier queries_;
  std::unique_ptr<BoxBatchCounter> counter_;  // cpu_pyramid only
  std::unique_ptr<GpuDepthPyramid> pyramid_;  // pyramid only
  std::unique_ptr<DepthPyramid> cpu_pyramid_;  // cpu_pyramid only
  Camera cam_;
  bool built_ = false, stale_ = false, resolved_ = false, use_pyramid_ = false;
  // cpu_pyramid: pixels drawn since level 0 was read (inclusive; empty when x0 > x1).
  PixelRect dirty_;
  void cpu_refresh();
  bool clean_under(const Aabb& box) const;  // no pixel of its footprint drawn since read back
  void clear_dirty();
  uint64_t proven_frame_ = 0;   // cpu_pyramid: pixels of the rectangles of the boxes the pyramid
                                // decided in this frame
  double proven_avg_ = -1;      // running average over the frames that used it (-1: none yet)
  uint32_t frames_off_ = 0;     // frames without the pyramid since it was last used
  std::vector<Aabb> boxes_;             // this batch's boxes
  std::vector<uint8_t> cheap_;          // per box: issued by issue_cheap()
  std::vector<PyramidProbe> probes_;    // and their probes
  std::vector<uint32_t> handle_;        // per box: its query handle, kZero (0 samples) or kPending
  std::vector<PyramidProbe> batch_;     // probes sent to the GPU
  std::vector<uint32_t> batch_index_, occluded_;
  Stats stats_;
};

}  // namespace occ
