#include "protocol/cluster/switch_step.hpp"

#include <algorithm>

#include "common/cull/front.hpp"

namespace occ {

namespace {
std::vector<uint32_t> sorted(const VisibleSet& s) {
  std::vector<uint32_t> ids(s.ids().begin(), s.ids().end());
  std::sort(ids.begin(), ids.end());
  return ids;
}
}  // namespace

SwitchStep::SwitchStep(const Renderables& r, const LodPolicy& lod, bool tracking)
    : r_(r), lod_(lod), tracking_(tracking) {}

uint64_t SwitchStep::coarsen(VisibleSet& visible, const Camera& cam) const {
  if (!tracking_) return 0;
  const LodSelector sel = lod_.selector(r_, cam);
  const std::vector<uint32_t> prime = coarsen_visible(sel, visible.ids());
  std::vector<uint32_t> gone;
  for (uint32_t id : visible.ids())
    if (!std::binary_search(prime.begin(), prime.end(), id)) gone.push_back(id);
  for (uint32_t id : gone) visible.erase(id);
  for (uint32_t id : prime) visible.insert(id);
  return front_hash(prime);
}

HcFrame SwitchStep::hc(uint32_t frame, VisibleSet& visible, const Camera& cam, OcclusionQueries& q, HcOptions o,
                       DiffSender& out, VisibilityHold* hold) const {
  const Hierarchy& h = r_.hierarchy();
  HcFrame result;
  const uint64_t fhash = coarsen(visible, cam);
  const LodSelector sel = lod_.selector(r_, cam);
  std::vector<uint32_t> start;
  if (tracking_) {
    std::vector<uint32_t> vnodes = nodes_of(r_, sorted(visible)), above;
    start = derive_occluded_front(h, vnodes, &above);
    const Frustum fr = cam.frustum();
    if (!lod_.visible_pixel_lod) vnodes = update_cut(h, sel, vnodes, &fr);
    start.insert(start.end(), vnodes.begin(), vnodes.end());  // occluded front first
    for (uint32_t a : above)  // what a root traversal would have queried above the fronts
      if (!fr.culls(h.node(a).box) && !visible_without_query(h.node(a).box, cam)) ++result.tests_above_fronts;
  }
  out.begin(frame, visible);
  o.visible_pixel_lod = lod_.visible_pixel_lod;
  o.start = start;
  o.on_visible = [&](uint32_t id) { out.visible(id); };
  o.stats = &result.stats;
  const std::vector<uint32_t> found = hardware_cull_lod(h, cam, q, sel, o);
  VisibleSet cur(visible.id_limit());
  for (uint32_t id : found) cur.insert(id);
  std::vector<uint32_t> held;
  if (hold) {
    for (uint32_t id : found) hold->seen(r_.node_of(id), frame);
    held = hold->held(r_, cam, sorted(visible), found, frame);
    for (uint32_t id : held) {
      cur.insert(id);
      out.visible(id);  // in V' already: nothing to send, except in full-sets mode (every id)
    }
    result.held = uint32_t(held.size());
  }
  result.eof = out.end(cur);
  result.eof.front_hash = fhash;
  result.eof.queries = result.stats.queries;
  for (uint32_t id : found) result.eof.triangles += r_.triangles(id);
  for (uint32_t id : held) result.eof.triangles += r_.triangles(id);
  visible = std::move(cur);
  return result;
}

}  // namespace occ
