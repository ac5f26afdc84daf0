#include "render_client/frame_drawer.hpp"

#include <iostream>

#include "common/cull/culling.hpp"
#include "common/gl/flush_schedule.hpp"
#include "common/gl/scene_renderer.hpp"

namespace occ {

namespace {
// --occlusion auto on a hardware GPU has two passes off: its pass 1 reads the frame's depth back to the CPU,
// which stalls a GPU's pipeline (on llvmpipe it is a copy, and the gate measures whether it pays).
OcclusionGate::Policy two_pass_policy(OcclusionGate::Policy flag, RendererClass renderer) {
  if (flag != OcclusionGate::Policy::automatic || renderer != RendererClass::hardware) return flag;
  std::cerr << "render_client: two passes off (--occlusion auto on a hardware renderer: no depth read-back)\n";
  return OcclusionGate::Policy::off;
}
}  // namespace

FrameDrawer::FrameDrawer(const ClientOptions& o, SceneGl& g)
    : g_(g),
      gate_({.policy = two_pass_policy(o.two_pass, g.ctx->renderer_class()), .alternate_every = o.alternate_every,
             .trial_after = 3, .start_on = false}),
      two_pass_(*g.ctx, *g.renderer, g.hierarchy(), *g.renderables) {}

FrameDrawer::Drawn FrameDrawer::draw(const Camera& cam, const std::vector<uint32_t>& ids, bool frustum_set,
                                     bool hold) {
  Drawn d;
  d.frustum_set = frustum_set;
  d.held = frustum_set && hold;
  d.two_pass = frustum_set && (d.held ? gate_.decided_occlusion() : gate_.occlusion(frames_));
  d.representative = !frustum_set || d.two_pass == gate_.decided_occlusion();
  // Frames of frustum sets leave the switch nodes idle (no OR; HC only frustum-culls): the render
  // client has the cores, so its draw is cut into parts as the single-process renderers' are
  // (llvmpipe rasterises one part while the next is binned); frames with occlusion keep the
  // cluster's fixed parts (flush_schedule.hpp). Two passes set their own.
  if (frustum_set)
    g_.renderer->set_flush_automatic();
  else
    g_.renderer->set_flush_triangles(FlushSchedule::kMaxPart);
  if (d.two_pass) {
    // After frames the switch culled, pass 1 starts from its last visible set; after frames
    // drawn in one pass, from everything.
    if (!two_pass_last_) switch_culled_last_ ? two_pass_.seed(last_visible_) : two_pass_.forget();
    d.tp = two_pass_.draw(cam, ids);
    d.st = d.tp.drawn;
    redrawn_ += d.tp.redrawn;
    ++used_;
  } else {
    g_.renderer->begin_frame(cam, true);
    d.st = g_.renderer->draw_renderables(*g_.renderables, ids, SceneRenderer::Mode::Shaded);
    g_.ctx->gl().Finish();
  }
  two_pass_last_ = d.two_pass;
  switch_culled_last_ = !frustum_set;
  if (!frustum_set) last_visible_ = ids;
  return d;
}

void FrameDrawer::measured(const Drawn& d, double render_ms) {
  if (!d.frustum_set) return;
  gate_.frame(d.two_pass, render_ms, d.st.triangles, d.set_triangles(), !d.held);
  ++frames_;
}

std::vector<uint32_t> FrameDrawer::drawn_ids(const Drawn& d, const std::vector<uint32_t>& ids) const {
  if (!d.two_pass) return ids;
  std::vector<uint32_t> drawn;
  two_pass_.drawn_ids(drawn);
  return drawn;
}

Image FrameDrawer::item_buffer(const Camera& cam, const std::vector<uint32_t>& ids) {
  g_.renderer->begin_id_frame(cam);
  g_.renderer->draw_renderables(*g_.renderables, ids, SceneRenderer::Mode::ItemIds);
  return g_.ctx->read_rgba();
}

size_t FrameDrawer::draw_overlay(const Camera& cam, const std::vector<uint32_t>& visible_ids) {
  if (!overlay_) overlay_ = std::make_unique<BoxOverlay>(*g_.ctx);
  std::vector<uint32_t> nodes;
  for (uint32_t r : visible_ids) nodes.push_back(g_.renderables->node_of(r));
  std::vector<Aabb> boxes;
  for (uint32_t leaf : occluded_leaves(g_.hierarchy(), cam, nodes)) boxes.push_back(g_.hierarchy().node(leaf).box);
  overlay_->draw(cam, boxes);
  g_.ctx->gl().Finish();
  return boxes.size();
}

void FrameDrawer::print_summary() const {
  if (frames_ == 0) return;
  std::cerr << "render_client: " << frames_ << " frames of frustum sets, " << used_
            << " of them culled here in two passes (" << redrawn_
            << " drawn again for a depth tie); two-pass gate: " << gate_.describe("two passes") << "\n";
}

}  // namespace occ
