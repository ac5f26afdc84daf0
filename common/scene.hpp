// The scene: shared meshes (instancing) placed by objects with double-precision transforms.
// Pure data, no GL. Loaded from glTF 2.0, generated procedurally, or laid out from copies of an
// asset (see scene_io.hpp).
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "common/math.hpp"

namespace occ {

// A contiguous range of a mesh's index buffer (whole triangles) with its mesh-space box.
// Big meshes are split into spatial clusters so a single merged mesh still culls.
struct MeshCluster {
  uint32_t first_index = 0;
  uint32_t index_count = 0;
  Aabb box;  // mesh space
};

struct Mesh {
  std::string name;
  std::vector<glm::vec3> positions;
  std::vector<glm::vec3> normals;  // same size as positions (computed when the file has none)
  std::vector<uint32_t> indices;   // triangle list, every index < positions.size()
  std::vector<MeshCluster> clusters;  // filled by split_mesh_clusters(); covers all indices

  uint64_t triangle_count() const { return indices.size() / 3; }
  Aabb box() const;  // mesh-space bounds of the referenced vertices
};

// One placed instance of a mesh.
struct Object {
  uint32_t mesh = 0;
  glm::dmat4 transform{1.0};  // mesh space -> world
  std::string name;
};

struct Scene {
  std::string source;  // what it was made from, for messages
  std::vector<Mesh> meshes;
  std::vector<Object> objects;

  Aabb bounds() const;               // world bounds of all objects
  uint64_t triangle_count() const;   // drawn triangles, counting every instance
  uint64_t content_hash() const;     // geometry, transforms (deterministic)
};

// Smooth per-vertex normals from area-weighted face normals (for meshes without NORMAL).
void compute_normals(Mesh& mesh);

// Reorders each mesh's triangles into spatial clusters of at most max_triangles triangles
// (recursive median split on triangle centroids, deterministic) and fills Mesh::clusters.
// Meshes at or under the threshold get one cluster.
void split_mesh_clusters(Scene& scene, uint32_t max_triangles);

}  // namespace occ
