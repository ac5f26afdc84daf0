#include "switch_node/cull_frame.hpp"

#include <algorithm>

#include "common/hash.hpp"

namespace occ {

CullFrame::CullFrame(GlContext& ctx, SceneRenderer& renderer, const Renderables& r, const Enclosures& sealed,
                     const ClusterConfig& config, const HcChoices& choices, Viewport vp, std::string other,
                     CpuOccluders* cpu)
    : ctx_(ctx),
      renderer_(renderer),
      r_(r),
      sealed_(sealed),
      config_(config),
      choices_(choices.resolved(hc_tests_on_cpu(cpu != nullptr, config, choices))),
      vp_(vp),
      other_(std::move(other)),
      step_(r, config, vp.height),
      // Sample counts only matter to visible-pixel LOD (a node with fewer than tau samples stops).
      querier_(ctx, choices.test, config.visible_pixel_lod && config.lod()),
      visible_(r.count()),
      cpu_(cpu) {
  if (*choices_.adaptive_queries) skipper_.emplace(r_.hierarchy().size());
  if (cpu_) geometry_seen_.assign(r_.hierarchy().size(), 0);
  if (hc_on_cpu()) raster_queries_.emplace(*cpu_);
  // The OR's occluders must not hide their own query boxes (SceneRenderer::set_occluder_offset):
  // every depth-only draw on this renderer is the OR's or occluder fusion's.
  renderer_.set_occluder_offset(true);
  restart();
}

void CullFrame::restart() {
  visible_.clear();
  std::fill(geometry_seen_.begin(), geometry_seen_.end(), 0);
  v_frustum_set_ = or_deferred_ = false;
  stream_ = DiffReceiver{};
  // The hold starts over too: on both nodes (a restarted one has no history) as at frame 0.
  hold_.reset();
  if (*choices_.visibility_hold > 0) hold_.emplace(r_.hierarchy().size(), uint32_t(*choices_.visibility_hold));
}

bool hc_tests_on_cpu(bool or_on_cpu, const ClusterConfig& config, const HcChoices& choices) {
  return or_on_cpu && !config.lod() && choices.test == HcTest::by_renderer;
}

bool CullFrame::hc_on_cpu() const { return hc_tests_on_cpu(cpu_ != nullptr, config_, choices_); }

void CullFrame::begin_or(const Camera& cam, bool occlusion) {
  occlusion_ = occlusion;
  drawn_.assign(r_.count(), 0);
  or_on_cpu_ = cpu_drawn_ = false;
  if (!occlusion_) return;
  // The OR on the CPU: at tau 0 HC tests there too, and this frame leaves GL alone.
  if (!hc_on_cpu()) renderer_.begin_frame(cam, false);
  if (cpu_) {
    cpu_->begin(cam);
    or_on_cpu_ = true;
  }
  // V a frustum set (the frame before was culled without occlusion): not drawn; HC draws what
  // it finds visible, nearest first (occluder fusion), unless the stream brings a culled V.
  or_deferred_ = v_frustum_set_ && choices_.occluder_fusion;
  totals_.ors_after_frustum_sets += or_deferred_;
  if (!or_deferred_) draw_v();
}

void CullFrame::draw_v() {
  std::vector<uint32_t> ids;
  ids.reserve(visible_.size());
  for (uint32_t id : visible_.ids())
    if (!drawn_[id]) {
      drawn_[id] = 1;
      ids.push_back(id);
    }
  std::sort(ids.begin(), ids.end());
  draw_depth(ids);
  // Rasterise now, while the other node's stream is awaited: llvmpipe rasterises at a flush
  // (SceneRenderer flushes only every ~20k triangles), so without it the rest of V waited for the
  // end of the OR and lengthened its tail, which HC waits for.
  ctx_.gl().Flush();
}

// Draws, depth only, those of `ids` that are not in this frame's depth buffer yet (the OR's
// streamed additions, occluder fusion); all of `ids` count as drawn from now on. Returns the
// renderables drawn.
std::vector<uint32_t> CullFrame::draw_new_occluders(std::span<const uint32_t> ids) {
  std::vector<uint32_t> fresh;
  for (uint32_t id : ids)
    if (!drawn_[id]) {
      drawn_[id] = 1;
      fresh.push_back(id);
    }
  if (!fresh.empty()) draw_depth(fresh);
  return fresh;
}

void CullFrame::draw_depth(std::span<const uint32_t> ids) {
  if (!or_on_cpu_) renderer_.draw_renderables(r_, ids, SceneRenderer::Mode::DepthOnly);
  // On the CPU: the OR's draws, and then HC's occluder fusion too (its leaves' own triangles are
  // tested against that depth, hc()).
  if (!or_on_cpu_ && !cpu_drawn_) return;
  for (uint32_t id : ids) cpu_->draw_leaf(r_.node_of(id), r_.level_of(id));
  cpu_drawn_ = cpu_drawn_ || !ids.empty();
}

void CullFrame::begin_stream(uint32_t frame) {
  in_ = Incoming{};
  in_.frame = frame;
}

Result<CullFrame::Stream> CullFrame::take(const wire::Message& m) {
  const std::string f = "frame " + std::to_string(in_.frame) + ": ";
  auto lost = [](std::string why) { return Error{std::move(why)}; };
  // The frame's first diff or EndOfFrame: in full-sets mode it replaces the set; only ids not in
  // V' were found visible (for the hold).
  auto start_frame = [&] {
    if (config_.full_sets && !in_.started) {
      if (hold_) {
        in_.before.assign(visible_.ids().begin(), visible_.ids().end());
        std::sort(in_.before.begin(), in_.before.end());
      }
      visible_.clear();
    }
    in_.started = true;
  };
  if (const auto* c = std::get_if<wire::Camera>(&m)) {
    if (in_.have_camera) return lost(f + "sent two cameras");
    in_.have_camera = true;
    if (auto err = viewport_mismatch(*c, vp_)) return lost(f + "sent " + *err);
    in_.expected_front = step_.coarsen(visible_, from_wire(*c));
    v_frustum_set_ = c->occlusion == 0;  // what V is once the stream is in
    return Stream::more;
  }
  if (const auto* d = std::get_if<wire::NodeDiff>(&m)) {
    if (!in_.have_camera) return lost(f + "sent its diff before its camera");
    start_frame();
    if (auto err = stream_.on_diff(visible_, *d)) return lost("desync: " + *err);
    if (hold_)  // the other node found these visible in this frame (added to V')
      for (uint32_t id : d->added)
        if (!config_.full_sets || !std::binary_search(in_.before.begin(), in_.before.end(), id))
          hold_->seen(r_.node_of(id), in_.frame);
    if (occlusion_ && !or_deferred_ && !draw_new_occluders(d->added).empty()) ctx_.gl().Flush();  // as in draw_v
    return Stream::more;
  }
  if (const auto* e = std::get_if<wire::EndOfFrame>(&m)) {
    if (!in_.have_camera) return lost(f + "sent its diff before its camera");
    start_frame();
    if (e->frame != in_.frame)
      return lost("ended frame " + std::to_string(e->frame) + ", expected " + std::to_string(in_.frame));
    if (auto err = stream_.on_end_of_frame(visible_, *e)) return lost("desync: " + *err);
    if (e->front_hash != in_.expected_front)
      return lost("desync: " + f + "front hash " + hex(e->front_hash) + " from " + other_ + ", " +
                  hex(in_.expected_front) + " here");
    // The OR left out a frustum set V; the other node's HC culled this one: the OR draws it now.
    if (occlusion_ && or_deferred_ && !v_frustum_set_) {
      or_deferred_ = false;
      draw_v();
    }
    return Stream::done;
  }
  return lost(f + "sent an unexpected " + std::string(wire::type_name(wire::type_of(m))));
}

HcFrame CullFrame::hc(uint32_t frame, const Camera& cam, DiffSender& out) {
  HcFrame hc;
  if (!occlusion_) {  // the frustum set: every box passes, nothing is learnt from it
    FrustumOnlyQueries all;
    hc = step_.hc(frame, visible_, cam, all, {.choices = choices_, .enclosures = &sealed_}, out);
    hc.stats.queries = hc.eof.queries = 0;
    ++totals_.frustum_frames;
  } else {
    HcOptions o{.choices = choices_, .skipper = skipper_ ? &*skipper_ : nullptr, .enclosures = &sealed_};
    // At tau 0 with the OR on the CPU, HC tests there too (RasterQueries): boxes against the
    // CPU's depth, and each leaf whose box shows by its own triangles (what the boxes of long,
    // thin or hollow objects cannot prove hidden); occluder fusion draws there. No GL this frame.
    const bool on_cpu = or_on_cpu_ && hc_on_cpu();
    if (choices_.occluder_fusion)
      o.occluders = [&](std::span<const uint32_t> found) {
        // Restores the GL state the queries need; the pyramid is stale where they were drawn.
        const std::vector<uint32_t> drawn = draw_new_occluders(found);
        if (drawn.empty()) return;
        std::vector<Aabb> boxes;
        boxes.reserve(drawn.size());
        for (uint32_t id : drawn) boxes.push_back(r_.hierarchy().node(r_.node_of(id)).box);
        if (on_cpu)
          raster_queries_->depth_added(boxes);
        else
          querier_.depth_added(boxes);
      };
    if (or_on_cpu_ && !config_.lod())
      o.geometry_shows = [this, frame](uint32_t leaf) {
        // A leaf whose triangles showed within the last kGeometryRecheck frames is taken to
        // show still (extra leaves only cost drawing them): tests go to the rest.
        uint32_t& seen = geometry_seen_[leaf];
        if (seen != 0 && frame < seen + kGeometryRecheck) return true;
        if (!cpu_->leaf_shows(leaf)) return false;
        seen = frame;
        return true;
      };
    if (on_cpu) {
      raster_queries_->begin(cam);
      hc = step_.hc(frame, visible_, cam, *raster_queries_, o, out, hold_ ? &*hold_ : nullptr);
    } else {
      // The OR's depth from the CPU (with levels of detail, or a --hc-test given), conservative,
      // into the buffer HC tests in GL, and HC's pyramid starts from it, not from GL's read back.
      const float* uploaded = nullptr;
      if (or_on_cpu_ && cpu_drawn_) {
        ctx_.write_depth(cpu_->raster().depth().data());
        uploaded = cpu_->raster().depth().data();
      }
      or_on_cpu_ = false;  // occluder fusion draws in GL, over it
      querier_.begin(cam, uploaded);
      hc = step_.hc(frame, visible_, cam, querier_, o, out, hold_ ? &*hold_ : nullptr);
      querier_.end();
    }
    or_on_cpu_ = false;
  }
  v_frustum_set_ = !occlusion_;
  or_deferred_ = false;
  count(hc);
  return hc;
}

void CullFrame::count(const HcFrame& hc) {
  ++totals_.frames;
  totals_.queries += hc.stats.queries;
  totals_.geometry_hidden += hc.stats.geometry_hidden;
  totals_.assumed_visible += hc.stats.skipped;
  totals_.skipped_occluded += hc.stats.skipped_occluded;
  totals_.pixel_stops += hc.stats.pixel_stops;
  totals_.hlods += hc.stats.hlods;
  totals_.tests_above_fronts += hc.tests_above_fronts;
  totals_.held += hc.held;
}

}  // namespace occ
