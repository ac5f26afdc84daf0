#include "switch_node/cull_frame.hpp"

#include <algorithm>
#include <stdexcept>

#include "common/cull/cpu_backend.hpp"
#include "common/gl/gl_cpu_pyramid_tests.hpp"
#include "common/gl/gl_depth_backend.hpp"
#include "common/gl/gl_pyramid_tests.hpp"
#include "common/gl/gl_query_tests.hpp"
#include "common/hash.hpp"

namespace occ {

BackendChoice choose_backend_for(const GlContext& ctx, const ClusterConfig& config, const HcChoices& hc,
                                 bool triangles_in_memory) {
  return choose_backend({.flag = hc.backend,
                         .software_renderer = ctx.renderer_class() == RendererClass::software,
                         .renderer = ctx.renderer(),
                         .tau = config.pixel_error,
                         .visible_pixel_lod = config.visible_pixel_lod,
                         .triangles_in_memory = triangles_in_memory},
                        hc.adaptive_queries, hc.visibility_hold);
}

HcChoices with_backend_defaults(HcChoices hc, const BackendChoice& c) {
  hc.backend = c.kind;
  hc.adaptive_queries = c.adaptive_queries;
  hc.visibility_hold = c.visibility_hold;
  return hc;
}

std::unique_ptr<OcclusionBackend> make_backend(const BackendChoice& c, GlContext& ctx, SceneRenderer& renderer,
                                               const Renderables& r, CpuOccluders* cpu, const ClusterConfig& config) {
  // Sample counts only matter to visible-pixel LOD (a node with fewer than tau samples stops).
  const bool counts = config.visible_pixel_lod && config.lod();
  switch (c.kind) {
    case BackendKind::cpu:
      if (!cpu) throw std::logic_error("make_backend: the CPU back end without the scene's triangles on the CPU");
      return std::make_unique<CpuBackend>(*cpu, r, !config.lod());
    case BackendKind::queries:
      return std::make_unique<GlDepthBackend>(ctx, renderer, r, std::make_unique<QueryTests>(ctx));
    case BackendKind::gpu_pyramid:
      return std::make_unique<GlDepthBackend>(ctx, renderer, r, std::make_unique<GpuPyramidTests>(ctx));
    case BackendKind::cpu_pyramid:
      return std::make_unique<GlDepthBackend>(ctx, renderer, r, std::make_unique<CpuPyramidTests>(ctx, counts));
  }
  throw std::logic_error("make_backend: unknown back end");
}

CullFrame::CullFrame(std::unique_ptr<OcclusionBackend> backend, const Renderables& r, const Enclosures& sealed,
                     const ClusterConfig& config, const HcChoices& choices, Viewport vp, std::string other)
    : backend_(std::move(backend)),
      r_(r),
      sealed_(sealed),
      config_(config),
      choices_(choices),
      vp_(vp),
      other_(std::move(other)),
      step_(r, config, vp.height),
      visible_(r.count()) {
  if (choices_.adaptive_queries.value_or(false)) skipper_.emplace(r_.hierarchy().size());
  restart();
}

void CullFrame::restart() {
  visible_.clear();
  backend_->restart();
  or_ = OrState::off;
  v_ = VSource::culled;
  stream_ = DiffReceiver{};
  // The hold starts over too: on both nodes (a restarted one has no history) as at frame 0.
  hold_.reset();
  if (choices_.visibility_hold.value_or(0) > 0)
    hold_.emplace(r_.hierarchy().size(), uint32_t(*choices_.visibility_hold));
}

void CullFrame::begin_or(const Camera& cam, bool occlusion) {
  if (!occlusion) {
    or_ = OrState::off;
    return;
  }
  backend_->begin(cam);
  // V a frustum set (the frame before was culled without occlusion): not drawn; HC draws what
  // it finds visible, nearest first (occluder fusion), unless the stream brings a culled V.
  or_ = v_ == VSource::frustum_set && choices_.occluder_fusion ? OrState::deferred : OrState::drawn;
  totals_.ors_after_frustum_sets += or_ == OrState::deferred;
  if (or_ == OrState::drawn) draw_v();
}

void CullFrame::draw_v() {
  std::vector<uint32_t> ids(visible_.ids().begin(), visible_.ids().end());
  std::sort(ids.begin(), ids.end());
  backend_->draw(ids);
  // Drawn now, while the other node's stream is awaited, not at the end of the OR.
  backend_->flush();
}

void CullFrame::begin_stream(uint32_t frame) {
  in_ = Incoming{};
  in_.frame = frame;
}

Result<CullFrame::Stream> CullFrame::take(const wire::Message& m) {
  const std::string f = "frame " + std::to_string(in_.frame) + ": ";
  auto lost = [](std::string why) { return Error{std::move(why)}; };
  if (const auto* c = std::get_if<wire::Camera>(&m)) {
    if (in_.have_camera) return lost(f + "sent two cameras");
    in_.have_camera = true;
    if (auto err = viewport_mismatch(*c, vp_)) return lost(f + "sent " + *err);
    in_.expected_front = step_.coarsen(visible_, from_wire(*c));
    v_ = c->occlusion == 0 ? VSource::frustum_set : VSource::culled;  // what V is once the stream is in
    return Stream::more;
  }
  if (const auto* d = std::get_if<wire::NodeDiff>(&m)) {
    if (!in_.have_camera) return lost(f + "sent its diff before its camera");
    if (auto err = stream_.on_diff(visible_, *d)) return lost("desync: " + *err);
    if (hold_)  // the other node found these visible in this frame (added to V')
      for (uint32_t id : d->added) hold_->seen(r_.node_of(id), in_.frame);
    if (or_ == OrState::drawn && backend_->draw(d->added) > 0) backend_->flush();  // as in draw_v
    return Stream::more;
  }
  if (const auto* e = std::get_if<wire::EndOfFrame>(&m)) {
    if (!in_.have_camera) return lost(f + "sent its diff before its camera");
    if (e->frame != in_.frame)
      return lost("ended frame " + std::to_string(e->frame) + ", expected " + std::to_string(in_.frame));
    if (auto err = stream_.on_end_of_frame(visible_, *e)) return lost("desync: " + *err);
    if (e->front_hash != in_.expected_front)
      return lost("desync: " + f + "front hash " + hex(e->front_hash) + " from " + other_ + ", " +
                  hex(in_.expected_front) + " here");
    // The OR left out a frustum set V; the other node's HC culled this one: the OR draws it now.
    if (or_ == OrState::deferred && v_ == VSource::culled) {
      or_ = OrState::drawn;
      draw_v();
    }
    return Stream::done;
  }
  return lost(f + "sent an unexpected " + std::string(wire::type_name(wire::type_of(m))));
}

HcFrame CullFrame::hc(uint32_t frame, const Camera& cam, DiffSender& out) {
  HcFrame hc;
  if (or_ == OrState::off) {  // the frustum set: every box passes, nothing is learnt from it
    FrustumOnlyQueries all;
    hc = step_.hc(frame, visible_, cam, all, {.choices = choices_, .enclosures = &sealed_}, out);
    hc.stats.queries = hc.eof.queries = 0;
    ++totals_.frustum_frames;
  } else {
    const uint64_t tested = backend_->counts().boxes_tested;
    HcOptions o{.choices = choices_, .skipper = skipper_ ? &*skipper_ : nullptr, .enclosures = &sealed_};
    backend_->begin_tests(frame, cam);
    hc = step_.hc(frame, visible_, cam, *backend_, o, out, hold_ ? &*hold_ : nullptr);
    backend_->end_tests();
    hc.eof.queries = uint32_t(backend_->counts().boxes_tested - tested);
  }
  v_ = or_ == OrState::off ? VSource::frustum_set : VSource::culled;
  or_ = OrState::off;
  count(hc);
  return hc;
}

void CullFrame::count(const HcFrame& hc) {
  ++totals_.frames;
  totals_.assumed_visible += hc.stats.skipped;
  totals_.skipped_occluded += hc.stats.skipped_occluded;
  totals_.pixel_stops += hc.stats.pixel_stops;
  totals_.hlods += hc.stats.hlods;
  totals_.tests_above_fronts += hc.tests_above_fronts;
  totals_.held += hc.held;
}

}  // namespace occ
