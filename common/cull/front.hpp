// Front tracking (paper 4.6) over the hierarchy with LOD selection, pure and GL-free.
//
// The cut of a traversal = visible front (nodes drawn, each at the representation HC chose) +
// occluded front (nodes whose box was occluded or outside the frustum). With monotone errors
// (LodData) a node is
//   over-refined   it and its parent satisfy the error bound (tau): coarsen to the refined ancestor;
//   refined        it satisfies, its parent does not;
//   under-refined  it does not satisfy: refine to its refined descendants.
//
// What each process does for frame f (camera f), in this order (all three identically):
//   1. V' = coarsen_visible(V_{f-1}): over-refined nodes -> their refined ancestor's HLOD, leaves
//      -> the coarser of (their level, the level the error allows). Never refines: under-refined
//      nodes stay, because only HC can decide what replaces them (queries, and visible-pixel LOD,
//      4.7.2, which deliberately keeps under-refined nodes with few visible pixels). The diff of
//      frame f is relative to V', EndOfFrame.front_hash = front_hash(V') (below; not set_hash)
//      checks that all three coarsened identically, EndOfFrame.set_hash = set_hash(V_f) checks
//      the result.
//   2. HC only: occluded front = derive_occluded_front(nodes of V') — the coarsest complement of
//      the visible front (every node not inside, above or equal to a visible node, whose parent
//      is above one). It needs no extra state, so it is the same whichever switch node did HC(f-1).
//      It is already coarsened: its nodes' parents do not satisfy (they are above V' nodes).
//      With visible-pixel LOD off, the visible front is also refined (update_cut, frustum-pruned).
//      HC issues the occluded front first, then the visible front, as its first query batch and
//      descends from there (culling.hpp).
#pragma once
#include <cstdint>
#include <span>
#include <vector>

#include "common/scene/hierarchy.hpp"
#include "common/lod/lod_select.hpp"
#include "common/math.hpp"

namespace occ {

// Topmost ancestor-or-self of `node` reachable through satisfying parents.
uint32_t refined_ancestor(const Hierarchy& h, const LodSelector& sel, uint32_t node);

// The LOD cut a fresh traversal without visibility produces: from the root, a non-empty node
// that satisfies is taken, otherwise its children are examined. Ascending ids.
std::vector<uint32_t> lod_cut(const Hierarchy& h, const LodSelector& sel);

// A cut (antichain of nodes) updated for the selector's camera: over-refined nodes coarsened,
// under-refined refined down. Subtrees outside `frustum` (if given) are dropped while refining.
// For a complete cut the result equals lod_cut(). Ascending ids, no duplicates.
std::vector<uint32_t> update_cut(const Hierarchy& h, const LodSelector& sel, std::span<const uint32_t> cut,
                                 const Frustum* frustum = nullptr);

// Step 1 above, on renderable ids. Ascending, no duplicates.
std::vector<uint32_t> coarsen_visible(const LodSelector& sel, std::span<const uint32_t> visible);

// The distinct nodes of a set of renderables, ascending.
std::vector<uint32_t> nodes_of(const Renderables& r, std::span<const uint32_t> renderables);

// Step 2 above: the occluded front implied by visible-front nodes (an antichain); {root} when
// empty. *ancestors (optional) = the strict ancestors of the visible front: the interior nodes
// a fresh root traversal would have tested and front tracking skips. Ascending ids.
std::vector<uint32_t> derive_occluded_front(const Hierarchy& h, std::span<const uint32_t> visible_nodes,
                                            std::vector<uint32_t>* ancestors = nullptr);

// 64-bit order-independent hash of a front (distinct ids). Not set_hash: the same IdSetSums
// (common/hash.hpp) as protocol's set_hash, but finalised by a Hasher over (count, sum, xor), so
// the value differs from set_hash of the same ids. Compare it only with other front_hash values.
uint64_t front_hash(std::span<const uint32_t> ids);

}  // namespace occ
