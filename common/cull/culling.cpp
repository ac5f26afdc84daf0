#include "common/cull/culling.hpp"

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
                           {.on_visible = on_visible,
                            .stats = stats,
                            .first_batch = HcOptions::kWholeFrontier,
                            .max_batch = HcOptions::kWholeFrontier});
}

std::vector<uint32_t> hardware_cull(const Hierarchy& h, const Camera& cam, OcclusionQueries& q,
                                    const std::function<void(uint32_t)>& on_visible, CullStats* stats) {
  return hardware_cull(Renderables(h, nullptr), cam, q, on_visible, stats);
}

namespace {

// hardware_cull_lod, batch by batch: take a batch from the frontier (a near-first shell), test its nodes (frustum, near the eye, skipped by adaptive queries, or a query: all
// queries of the batch in flight at once), read the results, then accept or refine each visible
// node; occluder fusion draws what the batch accepted before the next one is tested.
class LodTraversal {
 public:
  LodTraversal(const Hierarchy& h, const Camera& cam, OcclusionQueries& q, const LodSelector& sel, const HcOptions& o)
      : h_(h),
        cam_(cam),
        q_(q),
        sel_(sel),
        o_(o),
        st_(o.stats ? *o.stats : local_),
        skipper_(o.choices.adaptive_queries.value_or(false) ? o.skipper : nullptr),
        enclosures_(o.choices.sealed ? o.enclosures : nullptr),
        fusion_(o.choices.occluder_fusion),
        fr_(cam.frustum()),
        tau_(sel.tau()),
        pixel_lod_(o.visible_pixel_lod && tau_ > 0 && sel.renderables().lod() != nullptr) {}

  std::vector<uint32_t> run() {
    if (o_.start.empty())
      push(0);
    else
      for (uint32_t id : o_.start) push(id);
    while (take_batch()) {
      test_batch();
      read_results();
      accept_visible();
      if (fusion_ && !accepted_.empty()) q_.occluders_found(accepted_);
    }
    std::sort(out_.begin(), out_.end());
    return out_;
  }

 private:
  static constexpr uint64_t kNoQuery = ~uint64_t(0);

  void push(uint32_t id) { queue_.emplace(h_.node(id).box.distance2(cam_.eye), id); }

  bool take_batch() {
    batch_.clear();
    // A shell: the nearest box, at distance d0, and every box within 2 d0 (at least first_batch,
    // at most max_batch), so each batch reaches twice as far as the one before and what it finds
    // is drawn before farther boxes are tested.
    const double limit2 = queue_.empty() ? 0 : 4.0 * queue_.top().first;
    while (!queue_.empty() && batch_.size() < std::max<uint32_t>(o_.max_batch, 1) &&
           (batch_.size() < o_.first_batch || queue_.top().first <= limit2)) {
      batch_.push_back(queue_.top().second);
      queue_.pop();
    }
    return !batch_.empty();
  }

  // Every node of the batch: culled, visible without a query, or queried (issued, not read).
  void test_batch() {
    pending_.clear();
    visible_.clear();
    for (uint32_t id : batch_) {
      const HNode& n = h_.node(id);
      ++st_.nodes_visited;
      if (n.item_count == 0) continue;
      if (fr_.classify(n.box) == Containment::Outside) {
        ++st_.frustum_culled;
      } else if (enclosures_ && enclosures_->hides(id, cam_, sel_.viewport_height_px())) {
        ++st_.sealed;
      } else if (visible_without_query(n.box, cam_)) {
        ++st_.near_visible;
        visible_.emplace_back(id, kNoQuery);
      } else if (skipper_ && QuerySkipper::may_skip(n) && skipper_->skip(id)) {
        if (q_.cheap_tests()) {
          pending_.push_back({id, q_.issue_cheap(n.box), true});
        } else {
          ++st_.skipped;
          visible_.emplace_back(id, kNoQuery);
        }
      } else {
        pending_.push_back({id, q_.issue(n.box), false});
        ++st_.queries;
      }
    }
    if (!pending_.empty()) ++st_.levels;
  }

  void read_results() {
    for (const Pending& p : pending_) {
      const uint64_t samples = q_.result(p.handle);
      if (p.cheap && samples > 0) {  // skipped: assumed visible, as without the cheap test
        ++st_.skipped;
        visible_.emplace_back(p.id, kNoQuery);
        continue;
      }
      // The box shows; a leaf's own triangles may not (OcclusionQueries::leaf_may_show).
      const bool hidden_inside = samples > 0 && h_.node(p.id).leaf() && !q_.leaf_may_show(p.id);
      st_.geometry_hidden += hidden_inside;
      const bool shows = samples > 0 && !hidden_inside;
      if (skipper_) skipper_->record(p.id, shows);  // occluded: queried again from now on
      if (shows) {
        visible_.emplace_back(p.id, samples);
      } else {
        ++st_.occluded;
        st_.skipped_occluded += p.cheap;
      }
    }
    q_.end_batch();
  }

  // What a visible node is drawn as, or kNoNode to refine it. A leaf: its coarsest
  // representation where its query saw fewer than tau samples (4.7.2), else what the selector
  // chooses; an interior node: its HLOD where that meets tau, or where few pixels showed.
  uint32_t representation(uint32_t id, uint64_t samples) {
    const bool few_pixels = pixel_lod_ && samples != kNoQuery && double(samples) < tau_;
    if (h_.node(id).leaf()) {
      const uint32_t r = few_pixels ? sel_.coarsest(id) : sel_.renderable(id);
      if (few_pixels && r != sel_.renderable(id)) ++st_.pixel_stops;
      return r;
    }
    if (sel_.satisfies(id)) {
      ++st_.hlods;
      return id;
    }
    if (few_pixels && sel_.hlod_allowed(id)) {
      ++st_.hlods;
      ++st_.pixel_stops;
      return id;
    }
    return kNoNode;
  }

  // Accepts the batch's visible nodes in id order (streamed as they are) or queues their children.
  void accept_visible() {
    accepted_.clear();
    std::sort(visible_.begin(), visible_.end());
    for (auto [id, samples] : visible_) {
      const uint32_t r = representation(id, samples);
      if (r == kNoNode) {
        const HNode& n = h_.node(id);
        for (uint32_t ch = n.first_child; ch < n.first_child + n.child_count; ++ch) push(ch);
        continue;
      }
      out_.push_back(r);
      accepted_.push_back(r);
      if (o_.on_visible) o_.on_visible(r);
    }
  }

  const Hierarchy& h_;
  const Camera& cam_;
  OcclusionQueries& q_;
  const LodSelector& sel_;
  const HcOptions& o_;
  CullStats local_;
  CullStats& st_;
  QuerySkipper* const skipper_;
  const Enclosures* const enclosures_;
  const bool fusion_;
  const Frustum fr_;
  const double tau_;
  const bool pixel_lod_;
  // The frontier, ordered by distance from the eye.
  using Entry = std::pair<double, uint32_t>;  // (squared distance from the eye, node)
  std::priority_queue<Entry, std::vector<Entry>, std::greater<Entry>> queue_;
  std::vector<uint32_t> batch_, out_, accepted_;
  struct Pending {
    uint32_t id, handle;
    bool cheap;  // skipped by adaptive queries: only the cheap test (issue_cheap)
  };
  std::vector<Pending> pending_;
  std::vector<std::pair<uint32_t, uint64_t>> visible_;  // (node, samples; kNoQuery: none)
};

}  // namespace

std::vector<uint32_t> hardware_cull_lod(const Hierarchy& h, const Camera& cam, OcclusionQueries& q,
                                        const LodSelector& sel, const HcOptions& o) {
  return LodTraversal(h, cam, q, sel, o).run();
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
