// Levels of detail, the data (paper 4.1): LOD chains for every leaf, one HLOD per interior node
// and their object-space errors. Built by lod_build.cpp (simplifier: lod_simplify.cpp), cached by
// lod_cache.cpp, selected from by lod_select.hpp. No GL.
//
//   * Leaf LODs are built per distinct (mesh, cluster) in mesh space and shared by every instance
//     (a layout of 100 duplexes simplifies one duplex); a leaf's level-l error in world units is
//     the max over its items of the mesh-space error times the object's largest axis scale.
//   * An HLOD is built bottom-up from its children's coarsest representations (leaf level 3 or
//     child HLOD), merged in world space relative to the node's box centre (double origin, float
//     offsets: camera-relative rendering keeps working 1e7 from the origin), simplified to
//     LodParams::hlod_ratio of that input. Its error = max child error + the simplifier's error, so
//     errors are monotone: error(parent) >= error(any child representation). The simplifier and how
//     it keeps normals and colours: lod_simplify.hpp.
#pragma once
#include <array>
#include <limits>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "common/scene/hierarchy.hpp"
#include "common/scene/scene.hpp"

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
  // After release_geometry() (the GL driver holds the only copy) the arrays are empty; the
  // triangle count stays.
  bool released = false;
  uint64_t released_triangles = 0, released_vertices = 0;
  uint64_t triangles() const { return released ? released_triangles : indices.size() / 3; }
  uint64_t vertex_count() const { return released ? released_vertices : positions.size(); }
  void release_geometry();  // frees positions, normals, objects and indices; idempotent
};

class LodData {
 public:
  // Builds every LOD and HLOD (progress on a terminal when `progress_label` is non-empty).
  // lod_build.cpp.
  static LodData build(const Scene& scene, const Hierarchy& h, const LodParams& params,
                       const std::string& progress_label = "");
  // The binary cache (lod_cache.cpp, see also lod_cache.hpp).
  // Cache key: hierarchy fingerprint (scene content + hierarchy parameters) + LOD parameters +
  // format version.
  static uint64_t cache_key(const Hierarchy& h, const LodParams& params);

  // load() returns nullopt and says why (missing, truncated, bad magic, version,
  // stale key, checksum, inconsistent data) without ever trusting a size before checking it.
  // With lazy, the meshes come released and their arrays stay in the file (mapped()): what a
  // process under --geometry-budget streams from; the payload checksum is not checked then (see
  // load_scene_cache), each mesh's indices are when the upload reads them.
  static std::optional<LodData> load(const std::string& path, uint64_t expected_key, const Scene& scene,
                                     const Hierarchy& h, std::string* why, bool lazy = false);
  // Writes atomically (temporary file + rename). Returns an error message or nullopt.
  std::optional<std::string> save(const std::string& path) const;

  uint64_t key() const { return key_; }
  uint64_t hash() const { return hash_; }  // of the cache payload (goes into the scene fingerprint)

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
  // An interior node whose HLOD must never be drawn (its subtree holds BLEND items, which an
  // opaque HLOD would turn into occluders): its error becomes infinite, so no tau accepts it and
  // the traversal refines it. In memory only: not part of the cache or its hash (every process
  // decides the same from the same scene).
  void forbid_hlod(uint32_t node);
  bool hlod_allowed(uint32_t node) const { return hlod_of_node_[node] != kNoNode && errors_[node][0] < kForbidden; }
  static constexpr double kForbidden = std::numeric_limits<double>::infinity();

  const std::vector<LodMesh>& cluster_lods() const { return cluster_lods_; }
  const std::vector<uint32_t>& item_slots() const { return item_slot_; }
  const std::vector<LodMesh>& hlods() const { return hlods_; }
  uint64_t bytes() const;            // memory held by the meshes
  // Frees the arrays of one of this data's meshes (cluster_lods() or hlods()) once uploaded.
  // save() and the simplifier need them: a LodData with released meshes cannot be saved.
  void release(const LodMesh& m);
  bool geometry_released() const;
  uint64_t total_triangles() const;  // in all LODs and HLODs
  // After a lazy load: where the meshes' arrays lie (cluster LODs, then HLODs); else null.
  const MappedGeometry* mapped() const { return mapped_.get(); }
  // Index of one of this data's meshes in mapped()->meshes.
  size_t mapped_index(const LodMesh& m) const;

 private:
  friend struct LodBuilder;  // lod_build.cpp
  void finish_hash();        // hash_ = the hash of the cache payload (lod_cache.cpp)
  uint64_t key_ = 0, hash_ = 0;
  std::vector<LodMesh> cluster_lods_;   // per slot (distinct mesh+cluster): levels 1..3
  std::vector<uint32_t> item_slot_;     // per hierarchy item
  std::vector<LodMesh> hlods_;
  std::vector<uint32_t> hlod_of_node_;  // per node: index into hlods_ or kNoNode
  // per node: leaf: [l] = level-l error (l = 0..3); interior: all four = the HLOD's error.
  std::vector<std::array<double, kLeafLodLevels + 1>> errors_;
  std::shared_ptr<const MappedGeometry> mapped_;  // lazy loads
};

}  // namespace occ
