#include "common/culling.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <queue>

namespace occ {

bool visible_without_query(const Aabb& box, const Camera& cam) {
  const double ty = std::tan(cam.fovy_rad * 0.5), tx = ty * cam.aspect;
  // Distance from the eye to the farthest corner of the near rectangle, with a little slack.
  const double reach = cam.near_dist * std::sqrt(1.0 + tx * tx + ty * ty) * (1.0 + 1e-6);
  return box.distance2(cam.eye) <= reach * reach;
}

std::vector<uint32_t> frustum_cull(const Hierarchy& h, const Camera& cam, CullStats* stats) {
  CullStats local;
  CullStats& st = stats ? *stats : local;
  const Frustum fr = cam.frustum();
  std::vector<uint32_t> out, stack{0};
  while (!stack.empty()) {
    uint32_t id = stack.back();
    stack.pop_back();
    const HNode& n = h.node(id);
    ++st.nodes_visited;
    Containment c = fr.classify(n.box);
    if (c == Containment::Outside) {
      ++st.frustum_culled;
      continue;
    }
    if (n.leaf()) {
      if (n.item_count > 0) out.push_back(id);
      continue;
    }
    for (uint32_t ch = n.first_child; ch < n.first_child + n.child_count; ++ch) stack.push_back(ch);
  }
  std::sort(out.begin(), out.end());
  return out;
}

std::vector<uint32_t> occluded_leaves(const Hierarchy& h, const Camera& cam, std::span<const uint32_t> drawn_nodes) {
  std::vector<uint8_t> drawn(h.size(), 0);
  for (uint32_t n : drawn_nodes) drawn.at(n) = 1;
  std::vector<uint32_t> out;
  for (uint32_t leaf : frustum_cull(h, cam)) {
    bool covered = false;
    for (uint32_t n = leaf; n != kNoNode && !covered; n = h.node(n).parent) covered = drawn[n];
    if (!covered) out.push_back(leaf);
  }
  return out;
}

std::vector<uint32_t> hardware_cull(const Renderables& r, const Camera& cam, OcclusionQueries& q,
                                    const std::function<void(uint32_t)>& on_visible, CullStats* stats) {
  // With tau = 0 every accepted node is a leaf at full detail (LOD data, if any, is never used):
  // the LOD traversal from the root is exactly Algorithm 4.1.
  const LodSelector sel(r, cam, 1.0, 0.0);
  return hardware_cull_lod(r.hierarchy(), cam, q, sel,
                           {.choices = {.order = HcOrder::levels}, .on_visible = on_visible, .stats = stats});
}

std::vector<uint32_t> hardware_cull(const Hierarchy& h, const Camera& cam, OcclusionQueries& q,
                                    const std::function<void(uint32_t)>& on_visible, CullStats* stats) {
  return hardware_cull(Renderables(h, nullptr), cam, q, on_visible, stats);
}

std::vector<uint32_t> hardware_cull_lod(const Hierarchy& h, const Camera& cam, OcclusionQueries& q,
                                        const LodSelector& sel, const HcOptions& o) {
  CullStats local;
  CullStats& st = o.stats ? *o.stats : local;
  QuerySkipper* const skipper = o.choices.adaptive_queries ? o.skipper : nullptr;
  const std::function<void(std::span<const uint32_t>)> occluders = o.choices.occluder_fusion ? o.occluders : nullptr;
  const Frustum fr = cam.frustum();
  const double tau = sel.tau();
  const bool pixel_lod = o.visible_pixel_lod && tau > 0 && sel.renderables().lod() != nullptr;
  std::vector<uint32_t> out, accepted, batch;
  // The frontier: a level at a time (levels), or a queue ordered by distance (near_first).
  std::vector<uint32_t> next;
  using Entry = std::pair<double, uint32_t>;  // (squared distance from the eye, node)
  std::priority_queue<Entry, std::vector<Entry>, std::greater<Entry>> queue;
  const bool near_first = o.choices.order == HcOrder::near_first;
  auto push = [&](uint32_t id) {
    if (near_first)
      queue.emplace(h.node(id).box.distance2(cam.eye), id);
    else
      next.push_back(id);
  };
  if (o.start.empty())
    push(0);
  else
    for (uint32_t id : o.start) push(id);
  auto take_batch = [&] {
    batch.clear();
    if (!near_first) {
      batch.swap(next);
      return !batch.empty();
    }
    // A shell: the nearest box, at distance d0, and every box within 2 d0 (at least first_batch,
    // at most max_batch), so each batch reaches twice as far as the one before and what it finds
    // is drawn before farther boxes are tested.
    const double limit2 = queue.empty() ? 0 : 4.0 * queue.top().first;
    while (!queue.empty() && batch.size() < std::max<uint32_t>(o.max_batch, 1) &&
           (batch.size() < o.first_batch || queue.top().first <= limit2)) {
      batch.push_back(queue.top().second);
      queue.pop();
    }
    return !batch.empty();
  };
  constexpr uint64_t kNoQuery = ~uint64_t(0);
  std::vector<std::pair<uint32_t, uint32_t>> pending;  // (node, query handle)
  std::vector<std::pair<uint32_t, uint64_t>> visible;  // (node, samples)
  // What a visible leaf is drawn as: its coarsest representation where its query saw fewer than
  // tau samples (4.7.2), else what the selector chooses.
  auto leaf_renderable = [&](uint32_t id, uint64_t samples) {
    const bool few_pixels = pixel_lod && samples != kNoQuery && double(samples) < tau;
    return few_pixels ? sel.coarsest(id) : sel.renderable(id);
  };
  while (take_batch()) {
    pending.clear();
    visible.clear();
    for (uint32_t id : batch) {
      const HNode& n = h.node(id);
      ++st.nodes_visited;
      if (n.item_count == 0) continue;
      if (fr.classify(n.box) == Containment::Outside) {
        ++st.frustum_culled;
      } else if (visible_without_query(n.box, cam)) {
        ++st.near_visible;
        visible.emplace_back(id, kNoQuery);
      } else if (skipper && QuerySkipper::may_skip(n) && skipper->skip(id)) {
        ++st.skipped;
        visible.emplace_back(id, kNoQuery);
      } else {
        pending.emplace_back(id, q.issue(n.box));
        ++st.queries;
      }
    }
    if (!pending.empty()) ++st.levels;
    for (auto [id, handle] : pending) {
      const uint64_t samples = q.result(handle);
      if (skipper) skipper->record(id, samples > 0);
      if (samples > 0) {
        visible.emplace_back(id, samples);
      } else {
        ++st.occluded;
      }
    }
    q.end_batch();
    accepted.clear();
    std::sort(visible.begin(), visible.end());
    for (auto [id, samples] : visible) {
      const HNode& n = h.node(id);
      const bool few_pixels = pixel_lod && samples != kNoQuery && double(samples) < tau;
      uint32_t r = kNoNode;
      if (n.leaf()) {
        r = leaf_renderable(id, samples);
        if (few_pixels && r != sel.renderable(id)) ++st.pixel_stops;
      } else if (sel.satisfies(id)) {
        r = id;
        ++st.hlods;
      } else if (few_pixels && sel.hlod_allowed(id)) {
        r = id;
        ++st.hlods;
        ++st.pixel_stops;
      }
      auto accept = [&](uint32_t r) {
        out.push_back(r);
        accepted.push_back(r);
        if (o.on_visible) o.on_visible(r);
      };
      if (r != kNoNode) {
        accept(r);
      } else {
        for (uint32_t ch = n.first_child; ch < n.first_child + n.child_count; ++ch) push(ch);
      }
    }
    if (occluders && !accepted.empty()) occluders(accepted);
  }
  std::sort(out.begin(), out.end());
  return out;
}

std::vector<uint32_t> VisibilityHold::held(const Renderables& r, const Camera& cam, std::span<const uint32_t> prev,
                                           std::span<const uint32_t> found, uint32_t frame) const {
  std::vector<uint32_t> out;
  if (frames_ == 0 || prev.empty()) return out;
  const Hierarchy& h = r.hierarchy();
  // 1: a node of found; 2: a strict ancestor of one.
  std::vector<uint8_t> mark(h.size(), 0);
  for (uint32_t id : found) mark[r.node_of(id)] = 1;
  for (uint32_t id : found)
    for (uint32_t p = h.node(r.node_of(id)).parent; p != kNoNode && mark[p] == 0; p = h.node(p).parent) mark[p] = 2;
  const Frustum fr = cam.frustum();
  for (uint32_t id : prev) {
    const uint32_t n = r.node_of(id);
    if (mark[n] != 0 || !recent(n, frame) || fr.classify(h.node(n).box) == Containment::Outside) continue;
    bool under_found = false;
    for (uint32_t p = h.node(n).parent; p != kNoNode && !under_found; p = h.node(p).parent) under_found = mark[p] == 1;
    if (!under_found) out.push_back(id);
  }
  std::sort(out.begin(), out.end());
  return out;
}

bool QuerySkipper::skip(uint32_t node) {
  State& s = state_.at(node);
  if (s.remaining == 0) return false;
  --s.remaining;
  return true;
}

void QuerySkipper::record(uint32_t node, bool visible) {
  State& s = state_.at(node);
  if (!visible) {
    s = State{};
    return;
  }
  if (s.streak < kTrust) ++s.streak;
  if (s.streak < kTrust) return;
  s.wait = uint8_t(std::min<int>(kMaxWait, std::max<int>(2, 2 * s.wait)));
  s.remaining = s.wait;
}

std::vector<uint32_t> items_of_nodes(const Hierarchy& h, std::span<const uint32_t> nodes) {
  std::vector<uint32_t> items;
  for (uint32_t id : nodes) {
    const HNode& n = h.node(id);
    for (uint32_t i = n.first_item; i < n.first_item + n.item_count; ++i) items.push_back(i);
  }
  std::sort(items.begin(), items.end());
  items.erase(std::unique(items.begin(), items.end()), items.end());
  return items;
}

}  // namespace occ
