#include "common/cull/front.hpp"

#include <algorithm>

#include "common/hash.hpp"

namespace occ {

namespace {
void sort_unique(std::vector<uint32_t>& v) {
  std::sort(v.begin(), v.end());
  v.erase(std::unique(v.begin(), v.end()), v.end());
}
}  // namespace

uint32_t refined_ancestor(const Hierarchy& h, const LodSelector& sel, uint32_t node) {
  uint32_t a = node;
  while (h.node(a).parent != kNoNode && sel.satisfies(h.node(a).parent)) a = h.node(a).parent;
  return a;
}

std::vector<uint32_t> lod_cut(const Hierarchy& h, const LodSelector& sel) {
  std::vector<uint32_t> out, stack;
  if (h.size() > 0) stack.push_back(0);
  while (!stack.empty()) {
    const uint32_t id = stack.back();
    stack.pop_back();
    const HNode& n = h.node(id);
    if (n.item_count == 0) continue;
    if (sel.satisfies(id)) {
      out.push_back(id);
      continue;
    }
    for (uint32_t c = n.first_child; c < n.first_child + n.child_count; ++c) stack.push_back(c);
  }
  std::sort(out.begin(), out.end());
  return out;
}

std::vector<uint32_t> update_cut(const Hierarchy& h, const LodSelector& sel, std::span<const uint32_t> cut,
                                 const Frustum* frustum) {
  std::vector<uint32_t> out, stack;
  for (uint32_t id : cut) {
    if (h.node(id).item_count == 0) continue;
    const uint32_t a = refined_ancestor(h, sel, id);
    if (a != id || sel.satisfies(id)) {  // over-refined or refined
      out.push_back(a);
      continue;
    }
    stack.assign(1, id);  // under-refined: down to the refined descendants
    while (!stack.empty()) {
      const uint32_t x = stack.back();
      stack.pop_back();
      const HNode& n = h.node(x);
      if (n.item_count == 0) continue;
      if (x != id && frustum && frustum->culls(n.box)) continue;
      if (sel.satisfies(x)) {
        out.push_back(x);
        continue;
      }
      for (uint32_t c = n.first_child; c < n.first_child + n.child_count; ++c) stack.push_back(c);
    }
  }
  sort_unique(out);
  return out;
}

std::vector<uint32_t> coarsen_visible(const LodSelector& sel, std::span<const uint32_t> visible) {
  const Renderables& r = sel.renderables();
  const Hierarchy& h = r.hierarchy();
  std::vector<uint32_t> out;
  out.reserve(visible.size());
  for (uint32_t id : visible) {
    const uint32_t n = r.node_of(id);
    const uint32_t a = refined_ancestor(h, sel, n);
    if (a != n) {
      out.push_back(a);  // an interior node: its HLOD
    } else if (h.node(n).leaf()) {
      out.push_back(r.id(n, std::max(r.level_of(id), sel.leaf_level(n))));
    } else {
      out.push_back(id);
    }
  }
  sort_unique(out);
  return out;
}

std::vector<uint32_t> nodes_of(const Renderables& r, std::span<const uint32_t> renderables) {
  std::vector<uint32_t> out;
  out.reserve(renderables.size());
  for (uint32_t id : renderables) out.push_back(r.node_of(id));
  sort_unique(out);
  return out;
}

std::vector<uint32_t> derive_occluded_front(const Hierarchy& h, std::span<const uint32_t> visible_nodes,
                                            std::vector<uint32_t>* ancestors) {
  std::vector<uint32_t> out, above;
  if (visible_nodes.empty()) {
    if (h.size() > 0 && h.node(0).item_count > 0) out.push_back(0);
    if (ancestors) ancestors->clear();
    return out;
  }
  std::vector<uint8_t> mark(h.size(), 0);  // 1 = strict ancestor of a visible node, 2 = visible
  for (uint32_t v : visible_nodes) mark[v] = 2;
  for (uint32_t v : visible_nodes)
    for (uint32_t p = h.node(v).parent; p != kNoNode && mark[p] != 1; p = h.node(p).parent) {
      mark[p] = 1;  // (a visible node is never above another: the front is an antichain)
      above.push_back(p);
    }
  for (uint32_t a : above) {
    const HNode& n = h.node(a);
    for (uint32_t c = n.first_child; c < n.first_child + n.child_count; ++c)
      if (mark[c] == 0 && h.node(c).item_count > 0) out.push_back(c);
  }
  std::sort(out.begin(), out.end());
  if (ancestors) {
    std::sort(above.begin(), above.end());
    *ancestors = std::move(above);
  }
  return out;
}

uint64_t front_hash(std::span<const uint32_t> ids) {
  IdSetSums s;
  for (uint32_t id : ids) s.add(id);
  Hasher h;
  h.u64(ids.size());
  h.u64(s.sum);
  h.u64(s.x);
  return h.value();
}

}  // namespace occ
