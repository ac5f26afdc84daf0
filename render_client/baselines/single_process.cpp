#include "render_client/baselines/single_process.hpp"

#include <deque>
#include <queue>

#include "common/cull/culling.hpp"

namespace occ {

namespace {

using Entry = std::pair<double, uint32_t>;  // (squared distance to the eye, node)
using FrontToBack = std::priority_queue<Entry, std::vector<Entry>, std::greater<Entry>>;

void push_children(const Hierarchy& h, const Camera& cam, uint32_t id, FrontToBack& pq) {
  const HNode& n = h.node(id);
  for (uint32_t c = n.first_child; c < n.first_child + n.child_count; ++c)
    pq.emplace(h.node(c).box.distance2(cam.eye), c);
}

// Culling pass: the leaf goes into the depth buffer now, so it occludes what the traversal meets
// later; its colour comes from the shaded pass.
void draw_leaf(uint32_t id, SceneRenderer& r, BaselineStats& st) {
  uint32_t ids[1] = {id};
  r.draw_nodes(ids, SceneRenderer::Mode::DepthOnly);
  st.drawn.push_back(id);
}

// The frame: the accepted leaves, shaded, in item order after a depth clear, exactly as the
// brute-force reference draws them (so z-ties resolve the same way).
void shaded_pass(const Hierarchy& h, const Camera& cam, SceneRenderer& r, BaselineStats& st) {
  r.begin_frame(cam, false);  // depth only: the colour buffer still holds the cleared background
  st.nodes_drawn = st.drawn.size();
  st.triangles = r.draw_items(items_of_nodes(h, st.drawn), SceneRenderer::Mode::Shaded).triangles;
}

}  // namespace

BaselineStats render_stop_and_wait(const Hierarchy& h, const Camera& cam, SceneRenderer& r, BoxQuerier& q) {
  BaselineStats st;
  const Frustum fr = cam.frustum();
  FrontToBack pq;
  pq.emplace(0.0, 0u);
  while (!pq.empty()) {
    const uint32_t id = pq.top().second;
    pq.pop();
    const HNode& n = h.node(id);
    if (n.item_count == 0 || fr.classify(n.box) == Containment::Outside) continue;
    if (!visible_without_query(n.box, cam)) {
      q.begin(cam);
      const uint32_t handle = q.issue(n.box);
      const bool vis = q.result(handle) > 0;  // stop and wait
      q.reset();
      ++st.queries;
      if (!vis) continue;
    }
    if (n.leaf())
      draw_leaf(id, r, st);
    else
      push_children(h, cam, id, pq);
  }
  q.end();
  shaded_pass(h, cam, r, st);
  return st;
}

BaselineStats ChcRenderer::render(const Camera& cam, SceneRenderer& r, BoxQuerier& q) {
  BaselineStats st;
  const Frustum fr = cam.frustum();
  std::vector<uint8_t> now(h_.size(), 0);
  auto pull_up = [&](uint32_t id) {
    for (uint32_t a = id; a != kNoNode && !now[a]; a = h_.node(a).parent) now[a] = 1;
  };
  FrontToBack pq;
  std::deque<std::pair<uint32_t, uint32_t>> pending;  // (node, query handle), oldest first
  auto traverse = [&](uint32_t id) {
    if (h_.node(id).leaf())
      draw_leaf(id, r, st);
    else
      push_children(h_, cam, id, pq);
  };
  pq.emplace(0.0, 0u);
  while (!pq.empty() || !pending.empty()) {
    while (!pending.empty() && (pq.empty() || q.ready(pending.front().second))) {
      auto [id, handle] = pending.front();
      pending.pop_front();
      if (q.result(handle) == 0) continue;
      const bool was_visible = visible_[id];
      pull_up(id);
      if (!was_visible) traverse(id);  // previously visible leaves were drawn already
    }
    if (pq.empty()) continue;
    const uint32_t id = pq.top().second;
    pq.pop();
    const HNode& n = h_.node(id);
    if (n.item_count == 0 || fr.classify(n.box) == Containment::Outside) continue;
    if (visible_without_query(n.box, cam)) {
      pull_up(id);
      traverse(id);
      continue;
    }
    const bool was_visible = visible_[id];
    if (was_visible && !n.leaf()) {  // opened last frame: descend without a query
      traverse(id);
      continue;
    }
    q.begin(cam);
    pending.emplace_back(id, q.issue(n.box));
    ++st.queries;
    if (was_visible) traverse(id);  // previously visible leaf: draw now, the query updates it
  }
  q.reset();
  q.end();
  visible_.swap(now);
  shaded_pass(h_, cam, r, st);
  return st;
}

}  // namespace occ
