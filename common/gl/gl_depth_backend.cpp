#include "common/gl/gl_depth_backend.hpp"

namespace occ {

GlDepthBackend::GlDepthBackend(GlContext& ctx, SceneRenderer& renderer, const Renderables& r,
                               std::unique_ptr<GlDepthTests> tests)
    : OcclusionBackend(r.count()), ctx_(ctx), renderer_(renderer), r_(r), tests_(std::move(tests)) {
  renderer_.set_occluder_offset(true);
}

void GlDepthBackend::draw_depth(std::span<const uint32_t> fresh) {
  renderer_.draw_renderables(r_, fresh, SceneRenderer::Mode::DepthOnly);
}

void GlDepthBackend::depth_added(std::span<const uint32_t> fresh) {
  boxes_.clear();
  for (uint32_t id : fresh) boxes_.push_back(r_.hierarchy().node(r_.node_of(id)).box);
  tests_->depth_added(boxes_);  // restores the GL state the queries need
}

}  // namespace occ
