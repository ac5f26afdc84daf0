// Levels of detail (paper 4.1): LOD chains for every leaf, one HLOD per interior node, their
// object-space errors, the binary cache, the renderable-id space and the screen-space selection.
// No GL.
//
// Design (the final one; see also front.hpp and culling.hpp):
//   * Renderable ids. The paper makes "each LOD and HLOD a separate node in the scene graph". A
//     visible set V_f is a set of renderable ids: [0, N) (N = hierarchy nodes) means "node n at its
//     HLOD" for an interior node and "node n at full detail" for a leaf; N + 3 * leaf_index +
//     (l - 1) means "leaf at simplified level l" (l = 1..3). So the LOD choice travels with the id:
//     OR and RVG draw exactly what HC chose, including choices only HC can make (visible-pixel LOD,
//     paper 4.7.2, depends on query results); the wire format and set hashes are unchanged, and a
//     changed LOD is an ordinary diff entry (remove old id, add new id).
//   * Leaf LODs are built per distinct (mesh, cluster) in mesh space and shared by every instance
//     (a layout of 100 duplexes simplifies one duplex); a leaf's level-l error in world units is
//     the max over its items of the mesh-space error times the object's largest axis scale.
//   * An HLOD is built bottom-up from its children's coarsest representations (leaf level 3 or
//     child HLOD), merged in world space relative to the node's box centre (double origin, float
//     offsets: camera-relative rendering keeps working 1e7 from the origin), simplified to
//     LodParams::hlod_ratio of that input. Its error = max child error + the simplifier's error, so
//     errors are monotone: error(parent) >= error(any child representation). The simplifier is
//     meshopt_simplify on a position-welded copy (seams do not block collapses), falling back to
//     meshopt_simplifySloppy when topology stops it (disjoint buildings); normals are taken from
//     the original vertex whose normal best matches the new face (creases stay sharp), colours
//     from its object.
//   * Selection. err_px = err * H / (2 d tan(fovy/2)), d = distance from the eye to the node's box;
//     d = 0 (eye in or on the box) is +inf. A representation other than the original geometry is
//     used only when tau > 0 and err_px <= tau: with tau = 0 only leaves at level 0 are ever
//     selected, even if a simplified level reports error 0 (another triangulation changes pixels).
#pragma once
#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "common/camera.hpp"
#include "common/hierarchy.hpp"
#include "common/scene.hpp"

namespace occ {

constexpr uint32_t kLeafLodLevels = 3;  // simplified levels per leaf (level 0 = original)

struct LodParams {
  float level_ratio = 0.4f;   // leaf level l+1 targets this fraction of level l's triangles
  float hlod_ratio = 0.35f;   // an HLOD targets this fraction of its input (children's coarsest)
  uint32_t min_triangles = 4; // never simplify below this
  bool operator==(const LodParams&) const = default;
};

struct LodMesh {
  glm::dvec3 origin{0.0};               // positions are offsets from it (leaf LODs: mesh space, 0)
  std::vector<glm::vec3> positions;
  std::vector<glm::vec3> normals;       // same size
  std::vector<uint32_t> objects;        // HLOD: source object of each vertex (its colour); leaf: empty
  std::vector<uint32_t> indices;        // triangle list
  double error = 0;                     // object-space error (leaf LOD: mesh space; HLOD: world)
  uint64_t triangles() const { return indices.size() / 3; }
};

class LodData {
 public:
  // Builds every LOD and HLOD (progress on a terminal when `progress_label` is non-empty).
  static LodData build(const Scene& scene, const Hierarchy& h, const LodParams& params,
                       const std::string& progress_label = "");
  // Cache key: hierarchy fingerprint (scene content + hierarchy parameters) + LOD parameters +
  // format version.
  static uint64_t cache_key(const Hierarchy& h, const LodParams& params);

  // Binary cache. load() returns nullopt and says why (missing, truncated, bad magic, version,
  // stale key, checksum, inconsistent data) without ever trusting a size before checking it.
  static std::optional<LodData> load(const std::string& path, uint64_t expected_key, const Scene& scene,
                                     const Hierarchy& h, std::string* why);
  // Writes atomically (temporary file + rename). Returns an error message or nullopt.
  std::optional<std::string> save(const std::string& path) const;

  uint64_t key() const { return key_; }
  uint64_t hash() const { return hash_; }  // of the whole data (goes into the scene fingerprint)

  // Leaf LOD mesh of item `item` at level l (1..kLeafLodLevels).
  const LodMesh& item_lod(uint32_t item, uint32_t level) const {
    return cluster_lods_[item_slot_[item] * kLeafLodLevels + level - 1];
  }
  // HLOD of an interior node (nullptr for leaves and empty nodes).
  const LodMesh* hlod(uint32_t node) const {
    return hlod_of_node_[node] == kNoNode ? nullptr : &hlods_[hlod_of_node_[node]];
  }
  // World-space error: leaf at level l (0 for l = 0), interior node's HLOD (level ignored).
  double error(uint32_t node, uint32_t level) const { return errors_[node][level]; }
  // The coarsest representation's error (leaf level 3, interior HLOD).
  double coarsest_error(uint32_t node) const { return errors_[node][kLeafLodLevels]; }

  const std::vector<LodMesh>& cluster_lods() const { return cluster_lods_; }
  const std::vector<uint32_t>& item_slots() const { return item_slot_; }
  const std::vector<LodMesh>& hlods() const { return hlods_; }
  uint64_t bytes() const;            // memory held by the meshes
  uint64_t total_triangles() const;  // in all LODs and HLODs

 private:
  friend struct LodBuilder;
  void finish_hash();
  uint64_t key_ = 0, hash_ = 0;
  std::vector<LodMesh> cluster_lods_;   // per slot (distinct mesh+cluster): levels 1..3
  std::vector<uint32_t> item_slot_;     // per hierarchy item
  std::vector<LodMesh> hlods_;
  std::vector<uint32_t> hlod_of_node_;  // per node: index into hlods_ or kNoNode
  // per node: leaf: [l] = level-l error (l = 0..3); interior: all four = the HLOD's error.
  std::vector<std::array<double, kLeafLodLevels + 1>> errors_;
};

// Where the cache of a scene lives: DIR/<scene name>-<hash of spec>.lod; DIR = --lod-cache or
// $XDG_CACHE_HOME/occswitch or $HOME/.cache/occswitch or /tmp/occswitch.
std::string lod_cache_path(const std::string& cache_dir, const std::string& scene_spec);

// Loads the cache or builds (and saves) the data. Prints what it did to stderr prefixed by `who`:
// a rebuild message for a stale or corrupt cache, and a one-line summary (time, memory, triangles).
LodData load_or_build_lod(const Scene& scene, const Hierarchy& h, const LodParams& params,
                          const std::string& cache_dir, const std::string& scene_spec, const std::string& who);

// What the LODs can save. The coarsest cut is the better of "every leaf at its coarsest level" and
// "the root's children at their coarsest representation (HLOD or coarsest leaf level)"; `fraction`
// is 1 - its triangles / the scene's triangles. A scene whose LODs save less than 10 % or fewer than
// 20,000 triangles (2-4 ms of llvmpipe, at most) skips LOD selection: low-poly boxes, geometry the
// simplifier cannot reduce. It draws full detail as with --pixel-error 0 and pays neither the
// selection nor the LOD memory (load_and_build drops the data; every process decides the same).
struct LodBenefit {
  double fraction = 0;
  uint64_t saved_triangles = 0;
  static constexpr double kMinFraction = 0.10;
  static constexpr uint64_t kMinSavedTriangles = 20000;
  bool worth_selecting() const { return fraction >= kMinFraction && saved_triangles >= kMinSavedTriangles; }
};
LodBenefit lod_benefit(const LodData& lod, const Hierarchy& h);

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
  // Leaf: the coarsest level whose error meets tau (0 when tau = 0 or no LOD data).
  uint32_t leaf_level(uint32_t node) const;
  // The renderable a visible accepted node is drawn as (interior: its HLOD; leaf: leaf_level).
  uint32_t renderable(uint32_t node) const;
  // The coarsest renderable of a node (visible-pixel LOD: fewer visible pixels than tau).
  uint32_t coarsest(uint32_t node) const;
  const Renderables& renderables() const { return r_; }

 private:
  const Renderables& r_;
  const Hierarchy& h_;
  Camera cam_;
  double scale_ = 0;  // H / (2 tan(fovy/2))
  double tau_ = 0;
};

}  // namespace occ
