// The scene hierarchy: a deterministic sloppy n-ary tree of AABBs over drawable items
// (object x mesh cluster). Node ids are dense u32 in breadth-first order (root = 0, each
// level contiguous, children of a node contiguous). Every node's items are a contiguous range of
// Hierarchy::items, so "draw node n at full detail" = draw items [first_item, first_item+item_count).
// Identical input + parameters give identical ids on every process; fingerprint() proves it.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "common/math.hpp"
#include "common/scene/scene.hpp"

namespace occ {

struct NodeId {
  uint32_t value = 0;
  auto operator<=>(const NodeId&) const = default;
};
constexpr uint32_t kNoNode = 0xffffffffu;

struct BuildParams {
  uint32_t arity = 8;                  // max children per interior node
  uint32_t leaf_items = 1;             // max items in a leaf
  uint32_t cluster_triangles = 2048;   // meshes above this are split into clusters
  bool operator==(const BuildParams&) const = default;
};

// A drawable piece: one cluster of one object's mesh, with its world box.
struct Item {
  uint32_t object = 0;
  uint32_t cluster = 0;  // index into scene.meshes[object.mesh].clusters
  uint32_t triangles = 0;
  Aabb box;  // world space
};

struct HNode {
  uint32_t parent = kNoNode;
  uint32_t first_child = 0;
  uint32_t child_count = 0;  // 0 = leaf
  uint32_t first_item = 0;
  uint32_t item_count = 0;   // items of the whole subtree
  uint32_t depth = 0;
  uint64_t triangles = 0;    // of the whole subtree at full detail
  Aabb box;                  // world space, encloses all items of the subtree
  bool leaf() const { return child_count == 0; }
};

class Hierarchy {
 public:
  // Splits big meshes of `scene` into clusters (modifies index order) and builds the tree.
  static Hierarchy build(Scene& scene, const BuildParams& params);

  const std::vector<HNode>& nodes() const { return nodes_; }
  const HNode& node(uint32_t id) const { return nodes_[id]; }
  const std::vector<Item>& items() const { return items_; }
  size_t size() const { return nodes_.size(); }
  uint32_t depth() const { return depth_; }  // number of levels
  const BuildParams& params() const { return params_; }
  // 64-bit hash of the scene content, the build parameters and every node (ids, links, boxes).
  uint64_t fingerprint() const { return fingerprint_; }

 private:
  friend struct SceneCacheIo;  // scene_cache.cpp: saves and restores a built hierarchy
  std::vector<HNode> nodes_;
  std::vector<Item> items_;
  BuildParams params_;
  uint32_t depth_ = 0;
  uint64_t fingerprint_ = 0;
};

}  // namespace occ
