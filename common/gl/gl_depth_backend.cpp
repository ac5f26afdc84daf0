#include "common/gl/gl_depth_backend.hpp"

#include <cstdio>

namespace occ {

GlDepthBackend::GlDepthBackend(GlContext& ctx, SceneRenderer& renderer, const Renderables& r, HcStrategy strategy,
                     bool sample_counts)
    : OcclusionBackend(r.count()), ctx_(ctx), renderer_(renderer), r_(r), querier_(ctx, strategy, sample_counts) {
  renderer_.set_occluder_offset(true);
}

const char* GlDepthBackend::name() const {
  switch (querier_.mode()) {
    case HcStrategy::queries: return "queries";
    case HcStrategy::pyramid: return "gpu-pyramid";
    case HcStrategy::cpu_pyramid: return "cpu-pyramid";
  }
  return "?";
}

void GlDepthBackend::draw_depth(std::span<const uint32_t> fresh) {
  renderer_.draw_renderables(r_, fresh, SceneRenderer::Mode::DepthOnly);
}

void GlDepthBackend::depth_added(std::span<const uint32_t> fresh) {
  boxes_.clear();
  for (uint32_t id : fresh) boxes_.push_back(r_.hierarchy().node(r_.node_of(id)).box);
  querier_.depth_added(boxes_);  // restores the GL state the queries need
}

OcclusionCounts GlDepthBackend::counts() const {
  const HcQuerier::Stats& q = querier_.stats();
  OcclusionCounts c;
  c.boxes_tested = q.tests;
  c.boxes_occluded = q.occluded;
  const auto n = [](uint64_t v) { return std::to_string(v); };
  c.more.push_back(n(q.queries) + " occlusion queries issued");
  switch (querier_.mode()) {
    case HcStrategy::queries: break;
    case HcStrategy::pyramid:
      c.more.push_back(n(q.pyramid_occluded) + " proven occluded by the depth pyramid of " + n(q.pyramid_tested) +
                       " tested against it in " + n(q.dispatches) + " dispatches, " + n(q.builds) + " pyramid builds");
      break;
    case HcStrategy::cpu_pyramid: {
      char mp[32];
      std::snprintf(mp, sizeof mp, "%.2f", double(q.pyramid_pixels) / 1e6);
      c.more.push_back(n(q.batched) + " boxes in " + n(q.draws) + " batch draws");
      c.more.push_back(n(q.pyramid_occluded) + " proven occluded by the depth pyramid (" + mp +
                       " M pixels of their rectangles) and " + n(q.shown) + " shown, of " + n(q.pyramid_tested) +
                       " tested against it; " + n(q.builds) + " pyramid builds, " + n(q.refreshes) +
                       " refreshes after occluder fusion");
      break;
    }
  }
  if (q.cheap) c.more.push_back(n(q.assumed) + " of " + n(q.cheap) + " skipped by adaptive queries assumed visible");
  return c;
}

}  // namespace occ
