// HC's tests with GL's depth read back once a frame (glReadPixels) into a DepthPyramid on the CPU
// (--backend cpu-pyramid, where the CPU back end cannot run on a software renderer). The pyramid
// proves boxes occluded (DepthPyramid::occludes) and, without sample counts and where occluder
// fusion drew nothing since the read-back, boxes that show (DepthPyramid::shows: answered 1 with
// no test); the rest are counted by one draw per batch (BoxBatchCounter, no query objects),
// except those covering more than Policy::batch_max_pixels pixels or within reach of the near
// plane, which stay queries (the counting shader runs for every passing fragment). Frames whose
// pyramid decides boxes covering less than Policy::min_decided_screens viewports (a running
// average) do without it, retrying every kRetryFrames. A box shown on the CPU has a sample its
// query would count, and the batch draw counts the same samples: the visible sets are those of
// queries (without `sample_counts` a batch-counted or shown box answers 1 for any number).
// After occluder fusion drew, the drawn rectangle is read again and the levels above it rebuilt
// where it is no larger than the batch's rectangles; otherwise the boxes are tested against a
// pyramid stale there (depth only gets nearer: still conservative).
#pragma once
#include <cstdint>

#include "common/cull/hzb.hpp"
#include "common/gl/box_query.hpp"
#include "common/gl/hzb_query.hpp"

namespace occ {

class CpuPyramidTests final : public GlDepthTests {
 public:
  struct Policy {
    // Frames whose pyramid decides boxes whose rectangles cover fewer pixels than this many
    // viewports (average) do without it (0: always with it).
    double min_decided_screens = 0.25;
    int span = 16;                    // probe rectangles of at most span x span texels (hzb.hpp)
    double batch_max_pixels = 16384;  // larger boxes are queries, smaller ones counted by the batch draw
  };
  static constexpr uint32_t kRetryFrames = 8;
  struct Stats {
    uint64_t tests = 0;             // boxes tested (issue() and issue_cheap())
    uint64_t queries = 0;           // occlusion queries issued
    uint64_t batched = 0, draws = 0;  // boxes counted by batch draws, and the draws
    uint64_t pyramid_tested = 0;    // boxes tested against the pyramid
    uint64_t pyramid_occluded = 0;  // of those, proven occluded
    uint64_t pyramid_pixels = 0;    // pixels of the rectangles of the boxes it proved occluded
    uint64_t shown = 0;             // boxes proven to show (no test)
    uint64_t builds = 0;            // read-backs of the whole depth and builds
    uint64_t refreshes = 0;         // partial read-backs and rebuilds after occluder fusion
    uint64_t occluded = 0;          // boxes answered 0 samples
    uint64_t cheap = 0;             // issue_cheap() ones
    uint64_t assumed = 0;           // of those, not proven occluded: answered 1
  };

  // `sample_counts`: result() must be the number of samples (visible-pixel LOD), not just > 0.
  CpuPyramidTests(GlContext& ctx, bool sample_counts);
  CpuPyramidTests(GlContext& ctx, bool sample_counts, const Policy& policy);
  const char* name() const override { return "cpu-pyramid"; }
  void begin(const Camera& cam) override;
  void depth_added(std::span<const Aabb> drawn) override;
  void end() override { queries_.end(); }

  uint32_t issue(const Aabb& box) override;
  // The pyramid's test alone (frames that use it): boxes it cannot prove occluded answer 1.
  bool cheap_tests() const override { return use_pyramid_; }
  uint32_t issue_cheap(const Aabb& box) override;
  uint64_t result(uint32_t handle) override;
  void end_batch() override;

  OcclusionCounts counts() const override;
  const Stats& stats() const { return stats_; }

 private:
  static constexpr uint32_t kQueryBit = 1u << 31;
  void resolve();
  void refresh();  // level 0 read back and the levels built (or the dirty rectangle again)
  bool clean_under(const Aabb& box) const;  // no pixel of its footprint drawn since read back
  void counted_begin(const Camera& cam);
  uint32_t counted_issue(const Aabb& box);  // a query, or a box of the batch draw
  uint64_t counted_result(uint32_t h);

  GlContext& ctx_;
  const bool sample_counts_;
  Policy policy_;
  BoxQuerier queries_;
  BoxBatchCounter counter_;
  DepthPyramid pyramid_;
  PyramidBatch batch_;
  Camera cam_;
  bool built_ = false, stale_ = false, use_pyramid_ = false;
  PixelRect dirty_;             // pixels drawn since level 0 was read
  uint64_t proven_frame_ = 0;   // pixels of the rectangles of the boxes the pyramid decided this frame
  double proven_avg_ = -1;      // running average over the frames that used it (-1: none yet)
  uint32_t frames_off_ = 0;     // frames without the pyramid since it was last used
  Stats stats_;
};

}  // namespace occ
