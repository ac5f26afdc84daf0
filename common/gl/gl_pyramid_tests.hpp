// HC's tests with a GPU depth pyramid in front of the occlusion queries (--backend gpu-pyramid):
// each batch's boxes are first tested against the pyramid (GpuDepthPyramid) in one dispatch; only
// those it cannot prove occluded become queries (issued together, then read). Nothing is read
// back but one word per probe; the answers are the queries'.
//
// Which depth the pyramid holds: begin() starts a frame against a depth buffer drawn since the
// last build (the OR): the pyramid is built before its first use in the frame. depth_added()
// says more depth was drawn within the frame (occluder fusion). Depth only gets nearer then
// (GL_GREATER, depth writes on), so the pyramid built before still proves only true occlusion:
// it stays in use and is rebuilt only for batches of at least Policy::rebuild_min_probes probes.
#pragma once
#include <cstdint>

#include "common/gl/box_query.hpp"
#include "common/gl/hzb_query.hpp"

namespace occ {

class GpuPyramidTests final : public GlDepthTests {
 public:
  struct Policy {
    size_t rebuild_min_probes = 256;  // rebuild a stale pyramid (depth_added) for batches this large
    int span = 16;                    // probe rectangles of at most span x span texels (hzb.hpp)
  };
  struct Stats {
    uint64_t tests = 0;             // boxes tested (issue() and issue_cheap())
    uint64_t queries = 0;           // occlusion queries issued
    uint64_t pyramid_tested = 0;    // boxes tested against the pyramid
    uint64_t pyramid_occluded = 0;  // of those, proven occluded (no query)
    uint64_t builds = 0, dispatches = 0;
    uint64_t occluded = 0;          // boxes answered 0 samples
    uint64_t cheap = 0;             // issue_cheap() ones
    uint64_t assumed = 0;           // of those, not proven occluded: answered 1
  };

  explicit GpuPyramidTests(GlContext& ctx);
  GpuPyramidTests(GlContext& ctx, const Policy& policy);
  const char* name() const override { return "gpu-pyramid"; }
  void begin(const Camera& cam) override;
  void depth_added(std::span<const Aabb> drawn) override;
  void end() override { queries_.end(); }

  uint32_t issue(const Aabb& box) override;
  bool cheap_tests() const override { return true; }
  uint32_t issue_cheap(const Aabb& box) override;
  uint64_t result(uint32_t handle) override;
  void end_batch() override;

  OcclusionCounts counts() const override;
  const Stats& stats() const { return stats_; }

 private:
  void resolve();

  GlContext& ctx_;
  Policy policy_;
  BoxQuerier queries_;
  GpuDepthPyramid pyramid_;
  PyramidBatch batch_;
  Camera cam_;
  bool built_ = false, stale_ = false;
  Stats stats_;
};

}  // namespace occ
