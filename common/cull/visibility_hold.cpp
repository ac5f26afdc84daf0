#include "common/cull/visibility_hold.hpp"

#include <algorithm>

namespace occ {

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

}  // namespace occ
