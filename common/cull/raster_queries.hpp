// HC's box tests on the CPU (the CPU back end, cpu_backend.hpp): against the OR's depth as
// CpuOccluders drew it, with no renderer depth buffer, read-back or occlusion query. A box is
// occluded where a depth pyramid of that depth proves it (DepthPyramid::occludes), else where its
// faces, tested as DepthRaster::shows() tests triangles (conservative toward showing: a centre
// the renderer may cover counts, at the plane moved forward), find no pixel in front of the
// depth. Since the OR's CPU depth is never nearer than the renderer's of the same occluders, a
// box occluded here is occluded in every frame the renderer draws over them. As with the
// renderer's queries, the caller decides boxes the eye may see into before the near plane
// (visible_without_query; the traversal does). Answers 0 or 1 sample: no counts, so not for
// visible-pixel LOD. Occluder fusion draws into the same raster: depth_added() brings the
// pyramid up to date over what was drawn.
#pragma once
#include <cstdint>
#include <span>
#include <vector>

#include "common/cull/culling.hpp"
#include "common/cull/depth_raster.hpp"
#include "common/cull/hzb.hpp"

namespace occ {

class RasterQueries final : public OcclusionQueries {
 public:
  struct Stats {
    uint64_t tests = 0;             // boxes tested (issue and issue_cheap)
    uint64_t pyramid_occluded = 0;  // proven occluded by the pyramid
    uint64_t raster_occluded = 0;   // proven occluded by their faces
  };
  // `occluders`: the OR's depth, for the frame begin() starts; outlives this.
  explicit RasterQueries(CpuOccluders& occluders) : occ_(occluders) {}

  // A frame's tests from `cam` (the camera CpuOccluders::begin() drew the depth for).
  void begin(const Camera& cam);
  // More depth was drawn (occluder fusion): the world boxes of what was drawn.
  void depth_added(std::span<const Aabb> drawn);

  uint32_t issue(const Aabb& box) override;
  uint64_t result(uint32_t handle) override { return answers_[handle]; }
  void end_batch() override { answers_.clear(); }
  bool cheap_tests() const override { return true; }
  uint32_t issue_cheap(const Aabb& box) override;  // the pyramid only: 1 where it proves nothing

  const Stats& stats() const { return stats_; }

 private:
  uint32_t answer(uint64_t samples);
  bool pyramid_hides(const Aabb& box);

  CpuOccluders& occ_;
  Camera cam_;
  DepthPyramid pyramid_;
  PixelRect dirty_;  // level 0 behind the raster here
  std::vector<uint8_t> answers_;
  Stats stats_;
};

}  // namespace occ
