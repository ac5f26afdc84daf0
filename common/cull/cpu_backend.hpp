// The CPU occlusion back end: the OR's depth rasterised on the CPU (CpuOccluders, conservative
// against the renderer's own depth of the same triangles), HC's boxes tested against it
// (RasterQueries), and with leaf tests on, each leaf whose box shows tested by its own
// triangles. No renderer work in the frame. Its tests answer 0 or 1 sample: not for
// visible-pixel LOD (choose_backend() refuses it). CpuOccluders draws renderables at full detail
// only (a leaf at level 0): coarser levels and HLODs are left out of the depth, which only makes
// the tests prove less, so at tau > 0 the frames stay as conservative as the renderer's.
#pragma once
#include <cstdint>
#include <vector>

#include "common/cull/depth_raster.hpp"
#include "common/cull/occlusion_backend.hpp"
#include "common/cull/raster_queries.hpp"
#include "common/scene/hierarchy.hpp"

namespace occ {

class CpuBackend final : public OcclusionBackend {
 public:
  // `occluders`, `r`: outlive this. `leaf_tests`: test leaves by their triangles (full detail:
  // tau 0 only).
  CpuBackend(CpuOccluders& occluders, const Renderables& r, bool leaf_tests);

  const char* name() const override { return "cpu"; }
  void restart() override;

  uint32_t issue(const Aabb& box) override { return tests_.issue(box); }
  uint64_t result(uint32_t handle) override;
  void end_batch() override { tests_.end_batch(); }
  bool cheap_tests() const override { return true; }
  uint32_t issue_cheap(const Aabb& box) override { return tests_.issue_cheap(box); }
  // A leaf whose triangles showed within the last kRecheck frames is taken to show still (extra
  // leaves only cost drawing them): tests go to the rest.
  bool leaf_may_show(uint32_t leaf) override;

  OcclusionCounts counts() const override;

  static constexpr uint32_t kRecheck = 16;

 private:
  void clear_depth(const Camera& cam) override { occ_.begin(cam); }
  void draw_depth(std::span<const uint32_t> fresh) override;
  void start_tests(uint32_t frame, const Camera& cam) override;
  void depth_added(std::span<const uint32_t> fresh) override;

  CpuOccluders& occ_;
  const Renderables& r_;
  const bool leaf_tests_;
  RasterQueries tests_;
  uint32_t frame_ = 0;
  std::vector<uint32_t> seen_;  // per node: the last frame its triangles showed + 1 (0: none)
  std::vector<Aabb> boxes_;
  uint64_t occluded_ = 0, leaves_tested_ = 0, leaves_hidden_ = 0;
};

}  // namespace occ
