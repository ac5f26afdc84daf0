// Levels of detail, the selection (paper 4.1, Algorithm 4.1's error(node) < pixels of error):
// the renderable-id space, the screen-space error and the per-camera choice. No GL.
//
//   * Renderable ids. The paper makes "each LOD and HLOD a separate node in the scene graph". A
//     visible set V_f is a set of renderable ids: [0, N) (N = hierarchy nodes) means "node n at its
//     HLOD" for an interior node and "node n at full detail" for a leaf; N + 3 * leaf_index +
//     (l - 1) means "leaf at simplified level l" (l = 1..3). So the LOD choice travels with the id:
//     OR and RVG draw exactly what HC chose, including choices only HC can make (visible-pixel LOD,
//     paper 4.7.2, depends on query results); the wire format and set hashes are unchanged, and a
//     changed LOD is an ordinary diff entry (remove old id, add new id).
//   * Selection. err_px = err * H / (2 d tan(fovy/2)), d = distance from the eye to the node's box;
//     d = 0 (eye in or on the box) is +inf. A representation other than the original geometry is
//     used only when tau > 0 and err_px <= tau: with tau = 0 only leaves at level 0 are ever
//     selected, even if a simplified level reports error 0 (another triangulation changes pixels).
#pragma once
#include <cstdint>
#include <vector>

#include "common/camera.hpp"
#include "common/scene/hierarchy.hpp"
#include "common/lod/lod_data.hpp"

namespace occ {

// What the LODs can save. The coarsest cut is the better of "every leaf at its coarsest level" and
// "the root's children at their coarsest representation (HLOD or coarsest leaf level)"; `fraction`
// is 1 - its triangles / the scene's triangles. A scene whose LODs save a fraction under
// kMinFraction or fewer than kMinSavedTriangles triangles (little llvmpipe time) skips LOD
// selection: low-poly boxes, geometry the simplifier cannot reduce. It draws full detail as with
// --pixel-error 0 and pays neither the selection nor the LOD memory (load_and_build drops the data;
// every process decides the same).
struct LodBenefit {
  double fraction = 0;
  uint64_t saved_triangles = 0;
  static constexpr double kMinFraction = 0.10;
  static constexpr uint64_t kMinSavedTriangles = 20000;
  bool worth_selecting() const { return fraction >= kMinFraction && saved_triangles >= kMinSavedTriangles; }
};
LodBenefit lod_benefit(const LodData& lod, const Hierarchy& h);

// Forbids the HLOD of every interior node whose subtree holds an item with a BLEND material (an
// HLOD is drawn opaque and would occlude what the glass shows); returns how many. Call on
// loaded LOD data before selecting.
uint32_t forbid_blended_hlods(LodData& lod, const Scene& scene, const Hierarchy& h);

// The renderable-id space (see the design above). Works without LodData (tau = 0): the same ids
// exist, only level-0 leaves are ever used.
class Renderables {
 public:
  Renderables(const Hierarchy& h, const LodData* lod);
  uint32_t count() const { return count_; }  // N + 3 * leaves
  uint32_t node_of(uint32_t r) const { return r < n_ ? r : extra_leaf_[(r - n_) / kLeafLodLevels]; }
  uint32_t level_of(uint32_t r) const { return r < n_ ? 0 : (r - n_) % kLeafLodLevels + 1; }
  // Id of a leaf at level l, or of an interior node (level must be 0 for those).
  uint32_t id(uint32_t node, uint32_t level) const {
    return level == 0 ? node : n_ + leaf_index_[node] * kLeafLodLevels + level - 1;
  }
  uint64_t triangles(uint32_t r) const;
  const Hierarchy& hierarchy() const { return h_; }
  const LodData* lod() const { return lod_; }

 private:
  const Hierarchy& h_;
  const LodData* lod_;
  uint32_t n_ = 0, count_ = 0;
  std::vector<uint32_t> leaf_index_;  // per node: index among leaves (kNoNode for interior)
  std::vector<uint32_t> extra_leaf_;  // per leaf index: node id
};

// Screen-space projection of an object-space error (pixels). distance <= 0 (eye in or on the
// box) gives +inf; huge distances give ~0; never divides by zero.
double projected_error_px(double object_error, double distance, double viewport_height_px, double fovy_rad);

// LOD selection for one camera (Algorithm 4.1's error(node) < pixels of error).
class LodSelector {
 public:
  LodSelector(const Renderables& r, const Camera& cam, double viewport_height_px, double tau_px);
  double tau() const { return tau_; }
  double error_px(uint32_t node, uint32_t level) const;
  // Interior: its HLOD meets tau. Leaf: always (level 0 does).
  bool satisfies(uint32_t node) const;
  // Whether interior node `node` may be drawn as its HLOD (has one, not forbidden).
  bool hlod_allowed(uint32_t node) const { return r_.lod() && r_.lod()->hlod_allowed(node); }
  // Leaf: the coarsest level whose error meets tau (0 when tau = 0 or no LOD data).
  uint32_t leaf_level(uint32_t node) const;
  // The renderable a visible accepted node is drawn as (interior: its HLOD; leaf: leaf_level).
  uint32_t renderable(uint32_t node) const;
  // The coarsest renderable of a node (visible-pixel LOD: fewer visible pixels than tau).
  uint32_t coarsest(uint32_t node) const;
  const Renderables& renderables() const { return r_; }
  double viewport_height_px() const { return viewport_height_px_; }

 private:
  const Renderables& r_;
  const Hierarchy& h_;
  Camera cam_;
  double viewport_height_px_ = 0;  // H (projected_error_px divides by 2 d tan(fovy/2))
  double tau_ = 0;
};

}  // namespace occ
