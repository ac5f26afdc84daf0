// HC's tests as one occlusion query a box (BoxQuerier) against GL's depth: what a hardware GPU
// chooses (--backend queries). Answers are the queries' sample counts.
#pragma once
#include "common/gl/box_query.hpp"
#include "common/gl/hzb_query.hpp"

namespace occ {

class QueryTests final : public GlDepthTests {
 public:
  explicit QueryTests(GlContext& ctx) : queries_(ctx) {}
  const char* name() const override { return "queries"; }
  void begin(const Camera& cam) override;
  void depth_added(std::span<const Aabb>) override { queries_.begin(cam_); }
  void end() override { queries_.end(); }

  uint32_t issue(const Aabb& box) override;
  uint64_t result(uint32_t handle) override;
  void end_batch() override { queries_.reset(); }

  OcclusionCounts counts() const override;

 private:
  BoxQuerier queries_;
  Camera cam_;
  uint64_t tests_ = 0, occluded_ = 0;
};

}  // namespace occ
