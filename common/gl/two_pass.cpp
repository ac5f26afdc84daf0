#include "common/gl/two_pass.hpp"

#include <algorithm>
#include <optional>

#include "common/gl/box_query.hpp"

namespace occ {

TwoPassDrawer::TwoPassDrawer(GlContext& ctx, SceneRenderer& renderer, const Hierarchy& h, const Renderables& r)
    : ctx_(ctx), renderer_(renderer), h_(h), r_(r), shown_(r.count(), 1), memo_(h.size(), 0) {}

TwoPassDrawer::~TwoPassDrawer() {
  if (tie_query_) ctx_.gl().DeleteQueries(1, &tie_query_);
}

void TwoPassDrawer::forget() { std::fill(shown_.begin(), shown_.end(), 1); }

void TwoPassDrawer::seed(std::span<const uint32_t> shown_ids) {
  std::fill(shown_.begin(), shown_.end(), 0);
  for (uint32_t id : shown_ids) {
    if (id >= r_.count()) throw std::out_of_range("TwoPassDrawer: renderable " + std::to_string(id) + " out of range");
    shown_[id] = 1;
  }
}

bool TwoPassDrawer::node_hidden(uint32_t node, const Camera& cam) {
  if (memo_[node]) return memo_[node] == kHidden;
  const uint32_t parent = h_.node(node).parent;
  const bool hidden = (parent != kNoNode && node_hidden(parent, cam)) ||
                      pyramid_.hides(h_.node(node).box, cam, BoxQuerier::kRelativePad, kProofTexels);
  memo_[node] = hidden ? kHidden : kShown;
  touched_.push_back(node);
  return hidden;
}

std::pair<TwoPassDrawer::DrawPlace, TwoPassDrawer::DrawPlace> TwoPassDrawer::draw_places(uint32_t id) {
  renderer_.draw_order(r_, id, orders_);
  const uint64_t rank = (uint64_t(h_.node(r_.node_of(id)).first_item) << 8 | r_.level_of(id)) << 20;
  DrawPlace first{{~uint64_t(0), ~0u, 1e300}, ~uint64_t(0)}, last{{0, 0, -1e300}, 0};
  for (size_t i = 0; i < orders_.size(); ++i) {
    const DrawPlace place{orders_[i], rank + i};
    first = std::min(first, place);
    last = std::max(last, place);
  }
  return {first, last};
}

TwoPassDrawer::Frame TwoPassDrawer::draw(const Camera& cam, std::span<const uint32_t> ids) {
  const GlApi& gl = ctx_.gl();
  Frame f;
  first_.clear();
  second_.clear();
  for (uint32_t id : ids) {
    if (id >= r_.count()) throw std::out_of_range("TwoPassDrawer: renderable " + std::to_string(id) + " out of range");
    f.set_triangles += r_.triangles(id);
    (shown_[id] ? first_ : second_).push_back(id);  // second_: pass 2's candidates until tested
  }
  FlushSchedule& flush = renderer_.flush_schedule();
  const std::optional<uint32_t> parts = flush.fixed();
  flush.request(kFlushTriangles);
  // Pass 1. BLEND draws wait for the end of the frame, as one draw call's would.
  renderer_.begin_frame(cam, true, true);
  f.drawn += renderer_.draw_renderables(r_, first_, SceneRenderer::Mode::Shaded);
  ctx_.read_depth(pyramid_.level0(ctx_.width(), ctx_.height()));  // waits for pass 1
  pyramid_.build_levels();
  for (uint32_t n : touched_) memo_[n] = 0;
  touched_.clear();
  // Pass 2: what pass 1's depth does not hide; one tie query first (find_tie_candidates).
  drop_hidden(cam, f);
  find_tie_candidates();
  if (!checked_.empty()) {
    if (tie_query_ == 0) gl.CreateQueries(GL_SAMPLES_PASSED, 1, &tie_query_);
    renderer_.query_renderables(r_, checked_, tie_query_, GL_EQUAL);
  }
  if (!second_.empty()) f.drawn += renderer_.draw_renderables(r_, second_, SceneRenderer::Mode::Shaded);
  f.drawn += renderer_.end_frame();
  gl.Flush();  // the rasteriser takes the rest while pass 1's renderables are tested
  for (uint32_t id : first_) shown_[id] = !node_hidden(r_.node_of(id), cam);  // their own depth never hides them
  gl.Finish();
  const Rect tie = tie_rectangle(cam);
  f.first = uint32_t(first_.size());
  f.second = uint32_t(second_.size());
  flush.request(parts);
  if (tie.x0 <= tie.x1) redraw(cam, ids, tie, f);
  return f;
}

void TwoPassDrawer::drop_hidden(const Camera& cam, Frame& f) {
  size_t kept = 0;
  for (uint32_t id : second_) {
    const bool h = node_hidden(r_.node_of(id), cam);
    shown_[id] = !h;
    if (h)
      ++f.hidden;
    else
      second_[kept++] = id;
  }
  second_.resize(kept);
}

// A pass-2 draw that ties in depth with a pass-1 draw (they share a point: their boxes meet)
// shows there in one pass only when it comes first in one draw call's order: those pass-2
// renderables are checked, with one GL_EQUAL query against pass 1's depth.
void TwoPassDrawer::find_tie_candidates() {
  checked_.clear();
  first_last_.clear();
  for (uint32_t n : second_) {
    const Aabb& a = h_.node(r_.node_of(n)).box;
    std::optional<DrawPlace> n_first;  // computed once a box meets
    for (size_t k = 0; k < first_.size(); ++k) {
      const Aabb& b = h_.node(r_.node_of(first_[k])).box;
      if (!(a.min.x <= b.max.x && b.min.x <= a.max.x && a.min.y <= b.max.y && b.min.y <= a.max.y &&
            a.min.z <= b.max.z && b.min.z <= a.max.z))
        continue;
      if (first_last_.empty())
        for (uint32_t v : first_) first_last_.push_back(draw_places(v).second);
      if (!n_first) n_first = draw_places(n).first;
      if (*n_first < first_last_[k]) {
        checked_.push_back(n);
        break;
      }
    }
  }
}

// A tie: the passes' order may have decided those pixels. The checked renderables' screen
// rectangles (after the frame is finished, the tie query's result is there).
TwoPassDrawer::Rect TwoPassDrawer::tie_rectangle(const Camera& cam) {
  Rect r{ctx_.width(), ctx_.height(), -1, -1};
  GLuint64 ties = 0;
  if (!checked_.empty()) ctx_.gl().GetQueryObjectui64v(tie_query_, GL_QUERY_RESULT, &ties);
  if (!ties) return r;
  for (uint32_t n : checked_) {
    const BoxFootprint fp = box_footprint(h_.node(r_.node_of(n)).box, cam, {ctx_.width(), ctx_.height()});
    if (fp.kind == BoxFootprint::Kind::Offscreen) continue;
    const bool whole = fp.kind == BoxFootprint::Kind::NearPlane;
    r.x0 = std::min(r.x0, whole ? 0 : fp.x0);
    r.y0 = std::min(r.y0, whole ? 0 : fp.y0);
    r.x1 = std::max(r.x1, whole ? ctx_.width() - 1 : fp.x1);
    r.y1 = std::max(r.y1, whole ? ctx_.height() - 1 : fp.y1);
  }
  return r;
}

// Within the rectangle, the one-pass frame of everything that may reach it (the set's order
// restricted to them is the set's order; the rest draws nothing there).
void TwoPassDrawer::redraw(const Camera& cam, std::span<const uint32_t> ids, const Rect& rect, Frame& f) {
  const GlApi& gl = ctx_.gl();
  redraw_.clear();
  for (uint32_t id : ids) {
    const BoxFootprint fp = box_footprint(h_.node(r_.node_of(id)).box, cam, {ctx_.width(), ctx_.height()});
    if (fp.kind == BoxFootprint::Kind::NearPlane ||
        (fp.kind == BoxFootprint::Kind::OnScreen && fp.x0 <= rect.x1 && fp.x1 >= rect.x0 && fp.y0 <= rect.y1 &&
         fp.y1 >= rect.y0))
      redraw_.push_back(id);
  }
  gl.Enable(GL_SCISSOR_TEST);
  gl.Scissor(rect.x0, rect.y0, rect.x1 - rect.x0 + 1, rect.y1 - rect.y0 + 1);
  renderer_.begin_frame(cam, true);  // clears the rectangle only
  f.drawn += renderer_.draw_renderables(r_, redraw_, SceneRenderer::Mode::Shaded);
  gl.Finish();
  gl.Disable(GL_SCISSOR_TEST);
  f.redrawn = true;
  f.redrawn_pixels = uint64_t(rect.x1 - rect.x0 + 1) * uint64_t(rect.y1 - rect.y0 + 1);
}

}  // namespace occ
