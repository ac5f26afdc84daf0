// The occlusion back ends on GL's own depth: the OR draws depth only with the SceneRenderer (its
// occluder offset set, so the occluders never hide their own query boxes), and HC's boxes are
// tested against that depth by the GlDepthTests of one strategy (hzb_query.hpp): QueryTests,
// GpuPyramidTests or CpuPyramidTests. Every depth-only draw on the renderer is this back end's.
// Contracts: the context is current on the calling thread; it, the renderer and the
// renderables outlive this.
#pragma once
#include <memory>
#include <vector>

#include "common/cull/occlusion_backend.hpp"
#include "common/gl/context.hpp"
#include "common/gl/hzb_query.hpp"
#include "common/gl/scene_renderer.hpp"

namespace occ {

class GlDepthBackend final : public OcclusionBackend {
 public:
  GlDepthBackend(GlContext& ctx, SceneRenderer& renderer, const Renderables& r, std::unique_ptr<GlDepthTests> tests);

  const char* name() const override { return tests_->name(); }
  void flush() override { ctx_.gl().Flush(); }

  uint32_t issue(const Aabb& box) override { return tests_->issue(box); }
  uint64_t result(uint32_t handle) override { return tests_->result(handle); }
  void end_batch() override { tests_->end_batch(); }
  bool cheap_tests() const override { return tests_->cheap_tests(); }
  uint32_t issue_cheap(const Aabb& box) override { return tests_->issue_cheap(box); }

  OcclusionCounts counts() const override { return tests_->counts(); }
  const GlDepthTests& tests() const { return *tests_; }

 private:
  void clear_depth(const Camera& cam) override { renderer_.begin_frame(cam, false); }
  void draw_depth(std::span<const uint32_t> fresh) override;
  void start_tests(uint32_t, const Camera& cam) override { tests_->begin(cam); }
  void finish_tests() override { tests_->end(); }
  void depth_added(std::span<const uint32_t> fresh) override;

  GlContext& ctx_;
  SceneRenderer& renderer_;
  const Renderables& r_;
  const std::unique_ptr<GlDepthTests> tests_;
  std::vector<Aabb> boxes_;
};

}  // namespace occ
