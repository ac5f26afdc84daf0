// The occlusion back ends on GL's own depth: the OR draws depth only with the SceneRenderer (its
// occluder offset set, so the occluders never hide their own query boxes), and HC's boxes are
// tested by an HcQuerier of one strategy: an occlusion query a box (queries), a GPU depth
// pyramid in front of them (pyramid), or a depth pyramid read back to the CPU in front of batch
// counting draws (cpu_pyramid). Every depth-only draw on the renderer is this back end's.
// Contracts: the context is current on the calling thread; it, the renderer and the
// renderables outlive this.
#pragma once
#include "common/cull/occlusion_backend.hpp"
#include "common/gl/context.hpp"
#include "common/gl/hzb_query.hpp"
#include "common/gl/scene_renderer.hpp"

namespace occ {

class GlDepthBackend final : public OcclusionBackend {
 public:
  // `sample_counts`: result() gives the number of samples (visible-pixel LOD), not just > 0.
  GlDepthBackend(GlContext& ctx, SceneRenderer& renderer, const Renderables& r, HcStrategy strategy, bool sample_counts);

  const char* name() const override;
  void flush() override { ctx_.gl().Flush(); }

  uint32_t issue(const Aabb& box) override { return querier_.issue(box); }
  uint64_t result(uint32_t handle) override { return querier_.result(handle); }
  void end_batch() override { querier_.end_batch(); }
  bool cheap_tests() const override { return querier_.cheap_tests(); }
  uint32_t issue_cheap(const Aabb& box) override { return querier_.issue_cheap(box); }

  OcclusionCounts counts() const override;
  const HcQuerier& querier() const { return querier_; }

 private:
  void clear_depth(const Camera& cam) override { renderer_.begin_frame(cam, false); }
  void draw_depth(std::span<const uint32_t> fresh) override;
  void start_tests(uint32_t, const Camera& cam) override { querier_.begin(cam); }
  void finish_tests() override { querier_.end(); }
  void depth_added(std::span<const uint32_t> fresh) override;

  GlContext& ctx_;
  SceneRenderer& renderer_;
  const Renderables& r_;
  HcQuerier querier_;
  std::vector<Aabb> boxes_;
};

}  // namespace occ
