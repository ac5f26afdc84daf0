#include "common/scene/hierarchy.hpp"

#include <algorithm>
#include <deque>

#include "common/hash.hpp"

namespace occ {

namespace {

struct TmpNode {
  uint32_t begin, end;  // item range
  std::vector<uint32_t> children;
};

int longest_axis(const Aabb& b) {
  glm::dvec3 e = b.extent();
  return (e.x >= e.y && e.x >= e.z) ? 0 : (e.y >= e.z ? 1 : 2);
}

// Top-down build over items[begin, end): the range is split into up to `arity` groups by repeated
// median splits of the largest group along its longest centroid axis (a sloppy kd-style n-ary
// split: sibling boxes may overlap). Items are reordered in place so every subtree is contiguous.
uint32_t build_tmp(std::vector<Item>& items, uint32_t begin, uint32_t end, const BuildParams& p,
                   std::vector<TmpNode>& tmp) {
  uint32_t self = uint32_t(tmp.size());
  tmp.push_back({begin, end, {}});
  if (end - begin <= p.leaf_items) return self;
  std::vector<std::pair<uint32_t, uint32_t>> groups{{begin, end}};
  while (groups.size() < p.arity) {
    auto big = std::max_element(groups.begin(), groups.end(), [](auto a, auto b) {
      return a.second - a.first < b.second - b.first;
    });
    auto [gb, ge] = *big;
    if (ge - gb < 2) break;
    Aabb cb;
    for (uint32_t i = gb; i < ge; ++i) cb.grow(items[i].box.center());
    int axis = longest_axis(cb);
    uint32_t mid = gb + (ge - gb) / 2;
    std::nth_element(items.begin() + gb, items.begin() + mid, items.begin() + ge,
                     [axis](const Item& a, const Item& b) {
                       double ca = a.box.min[axis] + a.box.max[axis];
                       double cb2 = b.box.min[axis] + b.box.max[axis];
                       if (ca != cb2) return ca < cb2;
                       return a.object != b.object ? a.object < b.object : a.cluster < b.cluster;
                     });
    *big = {gb, mid};
    groups.insert(big + 1, {mid, ge});
  }
  for (auto [gb, ge] : groups) {
    uint32_t child = build_tmp(items, gb, ge, p, tmp);
    tmp[self].children.push_back(child);
  }
  return self;
}

}  // namespace

Hierarchy Hierarchy::build(Scene& scene, const BuildParams& params_in) {
  Hierarchy h;
  h.params_ = params_in;
  h.params_.arity = std::max<uint32_t>(h.params_.arity, 2);
  h.params_.leaf_items = std::max<uint32_t>(h.params_.leaf_items, 1);
  const BuildParams& p = h.params_;
  split_mesh_clusters(scene, p.cluster_triangles);

  for (uint32_t o = 0; o < scene.objects.size(); ++o) {
    const Object& obj = scene.objects[o];
    const Mesh& mesh = scene.meshes[obj.mesh];
    for (uint32_t c = 0; c < mesh.clusters.size(); ++c) {
      const MeshCluster& cl = mesh.clusters[c];
      h.items_.push_back({o, c, cl.index_count / 3, cl.box.transformed(obj.transform)});
    }
  }

  std::vector<TmpNode> tmp;
  build_tmp(h.items_, 0, uint32_t(h.items_.size()), p, tmp);

  // Breadth-first renumbering: ids are dense, levels contiguous, siblings contiguous.
  std::deque<std::pair<uint32_t, uint32_t>> queue{{0u, kNoNode}};  // (tmp index, parent id)
  while (!queue.empty()) {
    auto [t, parent] = queue.front();
    queue.pop_front();
    uint32_t id = uint32_t(h.nodes_.size());
    HNode n;
    n.parent = parent;
    n.depth = parent == kNoNode ? 0 : h.nodes_[parent].depth + 1;
    n.first_item = tmp[t].begin;
    n.item_count = tmp[t].end - tmp[t].begin;
    for (uint32_t i = tmp[t].begin; i < tmp[t].end; ++i) {
      n.box.grow(h.items_[i].box);
      n.triangles += h.items_[i].triangles;
    }
    n.child_count = uint32_t(tmp[t].children.size());
    h.nodes_.push_back(n);
    if (parent != kNoNode && h.nodes_[parent].first_child == 0) h.nodes_[parent].first_child = id;
    for (uint32_t c : tmp[t].children) queue.emplace_back(c, id);
    h.depth_ = std::max(h.depth_, n.depth + 1);
  }

  Hasher fh;
  fh.u64(scene.content_hash());
  fh.u32(p.arity);
  fh.u32(p.leaf_items);
  fh.u32(p.cluster_triangles);
  fh.u64(h.nodes_.size());
  for (const HNode& n : h.nodes_) {
    for (uint32_t v : {n.parent, n.first_child, n.child_count, n.first_item, n.item_count}) fh.u32(v);
    for (int a = 0; a < 3; ++a) {
      fh.f64(n.box.min[a]);
      fh.f64(n.box.max[a]);
    }
  }
  fh.u64(h.items_.size());
  for (const Item& it : h.items_) {
    fh.u32(it.object);
    fh.u32(it.cluster);
  }
  h.fingerprint_ = fh.value();
  return h;
}

}  // namespace occ
