// Objects sealed inside others (the bars inside a bridge's concrete, parts inside a closed
// housing): no camera outside the solid that seals them sees them, so HC need not test them.
// Found once per scene, without GL, from geometry alone:
//   a solid is an object whose mesh is closed (every edge shared by exactly two triangles, in
//   opposite directions: watertight and consistently wound), convex (every vertex on the inner
//   side of every triangle's plane), opaque (OPAQUE material, or none) and, unless double-sided,
//   wound with its front faces outwards under a transform that keeps orientation; small meshes
//   only (kMaxSolidTriangles): concrete members, housings, walls as exported;
//   an item (object x cluster) is sealed when all its world vertices lie strictly inside one solid
//   (another object), `margin` from its nearest face plane.
// Why that hides it, exactly: a ray from an eye outside the solid that reaches the item enters the
// solid first, through a front face at least `margin` nearer; the solid's front faces cover its
// silhouette without cracks (shared edges, identical vertices); so wherever the item would leave
// a fragment the solid leaves a nearer one, if (1) the solid is drawn there unclipped: the near
// plane does not cut it (visible_without_query(solid box) is false) and (2) the item's projection
// stays inside the solid's by more than the rasteriser's snapping: the margin seen from the eye
// spans at least kMinMarginPixels pixels, and (3) no section plane of the camera cuts a solid
// (common/section.hpp: the cut opens it). And if the solid itself is not drawn (culled: outside
// the frustum or occluded), whatever hides it hides what it seals. With LODs (tau > 0) an
// interior node drawn as its HLOD may not seal its items; they are then within that node's error
// bound, as everything the HLOD stands for.
// A node is sealed when every item of its subtree is; hides() tests it for one camera.
#pragma once
#include <cstdint>
#include <vector>

#include "common/camera.hpp"
#include "common/scene/hierarchy.hpp"
#include "common/scene/scene.hpp"

namespace occ {

class Enclosures {
 public:
  static constexpr uint32_t kMaxSolidTriangles = 256;
  // The margin must span this many pixels as seen from the eye (the rasteriser snaps vertices to
  // 1/256 pixel on llvmpipe, 1/256 or finer on GPUs: each edge moves at most half a step).
  static constexpr double kMinMarginPixels = 1.0 / 64;

  Enclosures() = default;  // nothing sealed
  // Needs the meshes' geometry (before Mesh::release_geometry); a released mesh seals nothing.
  static Enclosures find(const Scene& scene, const Hierarchy& h);

  // True when node `id` is sealed and no fragment of it can show for `cam` on a viewport
  // `viewport_height_px` pixels high.
  bool hides(uint32_t id, const Camera& cam, double viewport_height_px) const;
  bool sealed(uint32_t id) const { return !nodes_.empty() && nodes_[id].margin > 0; }
  uint32_t sealed_items() const { return sealed_items_; }
  uint32_t solids() const { return solids_; }  // objects that seal some item

 private:
  struct Node {
    Aabb solids;        // union of the world boxes of the solids sealing its items
    double margin = 0;  // the smallest margin of its items; 0: not sealed
  };
  std::vector<Node> nodes_;
  uint32_t sealed_items_ = 0, solids_ = 0;
};

}  // namespace occ
