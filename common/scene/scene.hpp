// The scene: shared meshes (instancing) placed by objects with double-precision transforms.
// Pure data, no GL. Loaded from glTF 2.0, generated procedurally, or laid out from copies of an
// asset (see scene_io.hpp).
#pragma once
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "common/image.hpp"
#include "common/math.hpp"
#include "common/scene/mapped_geometry.hpp"

namespace occ {

// ---------------------------------------------------------------------------------- materials
// glTF 2.0 metallic-roughness materials reduced to what the renderers draw: base colour (factor x
// texture x COLOR_0), alpha mode, double-sidedness, and KHR_materials_unlit. Colours are used as
// stored (no sRGB conversion): the factor, the texture's texels and COLOR_0 multiply as they are.

enum class AlphaMode : uint8_t { Opaque, Mask, Blend };
const char* alpha_mode_name(AlphaMode m);  // "OPAQUE", "MASK", "BLEND"

// glTF sampler values are OpenGL enums: filters 9728 NEAREST, 9729 LINEAR, 9984..9987
// *_MIPMAP_*; wraps 33071 CLAMP_TO_EDGE, 33648 MIRRORED_REPEAT, 10497 REPEAT. -1 = unset (the
// renderer then uses LINEAR / LINEAR_MIPMAP_LINEAR).
struct Sampler {
  int32_t mag_filter = -1, min_filter = -1;
  int32_t wrap_s = 10497, wrap_t = 10497;
  bool operator==(const Sampler&) const = default;
};

// A glTF texture: an image of Scene::images sampled with a sampler.
struct Texture {
  uint32_t image = 0;
  Sampler sampler;
};

struct Material {
  std::string name;
  glm::vec4 base_color{1.0f};         // baseColorFactor (RGBA)
  int32_t base_color_texture = -1;    // index into Scene::textures, or -1
  AlphaMode alpha_mode = AlphaMode::Opaque;
  float alpha_cutoff = 0.5f;          // MASK: fragments with alpha < cutoff are discarded
  bool double_sided = false;          // false: back faces are culled (glTF)
  bool unlit = false;                 // KHR_materials_unlit: base colour without lighting
  bool object_color = false;          // base colour from a hash of the object index (glTF
                                      // primitives without a material: the factor is ignored)
};

// Mesh::material for geometry without any material (the generated city, hard:*): a per-object hashed
// colour, opaque, double-sided.
constexpr uint32_t kNoMaterial = 0xffffffffu;

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
  std::vector<glm::vec2> uvs;      // empty, or same size as positions: the base colour texture's
                                   // TEXCOORD_n (glTF: (0,0) = the image's top-left texel)
  std::vector<uint32_t> colors;    // empty, or same size as positions: COLOR_0 as RGBA8
                                   // (r in the low byte); multiplies the base colour
  uint32_t material = kNoMaterial; // index into Scene::materials
  // Shaded with each triangle's own normal (the plane it lies in), not `normals`: glTF requires
  // flat normals for a primitive without NORMAL (the BIM exports give none). `normals` then
  // holds smooth ones, for the vertex layout and the LOD builders.
  bool flat = false;

  // After release_geometry() the vertex and index arrays are gone (the GL driver holds the only
  // copy); the counts, the box and the clusters stay.
  bool released = false;
  uint64_t released_triangles = 0, released_vertices = 0;
  Aabb released_box;

  uint64_t triangle_count() const { return released ? released_triangles : indices.size() / 3; }
  uint64_t vertex_count() const { return released ? released_vertices : positions.size(); }
  Aabb box() const;  // mesh-space bounds of the referenced vertices
  // Frees positions, normals, indices, uvs and colours (their memory, not just their size),
  // keeping triangle_count(), vertex_count(), box() and clusters. Idempotent.
  void release_geometry();
};

// One placed instance of a mesh.
struct Object {
  uint32_t mesh = 0;
  glm::dmat4 transform{1.0};  // mesh space -> world
  std::string name;
};

// A file a scene was read from, as it was when read: what tells a scene cache of it stale.
struct SourceFile {
  std::string path;
  uint64_t size = 0;
  int64_t mtime_ns = 0;
  bool operator==(const SourceFile&) const = default;
};
// path as it is now; nullopt when it cannot be stat'ed.
std::optional<SourceFile> source_file(const std::string& path);

struct Scene {
  std::string source;  // what it was made from, for messages
  std::vector<SourceFile> files;  // the files it was read from (a glTF, its buffers and images)
  std::vector<Mesh> meshes;
  std::vector<Object> objects;
  std::vector<Material> materials;
  std::vector<Texture> textures;
  std::vector<Image> images;  // decoded RGBA8, top row first
  // Triangles of the source left out of the meshes because they have no area
  // (drop_zero_area_triangles), counted per instance like triangle_count().
  uint64_t zero_area_triangles = 0;
  // Triangles of the source left out because they repeat another of their mesh
  // (drop_repeated_triangles), counted per instance.
  uint64_t repeated_triangles = 0;
  // Set when the meshes were loaded released from the scene cache, their arrays left in the
  // mapped file (load_scene_cache with lazy): mapped->meshes[m] is where mesh m's arrays lie.
  std::shared_ptr<const MappedGeometry> mapped;

  Aabb bounds() const;               // world bounds of all objects
  uint64_t triangle_count() const;   // drawn triangles, counting every instance
  // Geometry, transforms and materials (what the renderers draw, also what decides occluders:
  // BLEND objects never occlude), deterministic. Throws std::logic_error once a mesh's geometry
  // has been released (the hierarchy fingerprint holds the hash from before).
  uint64_t content_hash() const;
  bool geometry_released() const;  // any mesh released
  // Whether mesh m has COLOR_0 / texture coordinates for every vertex (also a mesh left in the
  // mapped cache, whose arrays are not in memory).
  bool mesh_has_colors(uint32_t m) const;
  bool mesh_has_uvs(uint32_t m) const;
  // The material of mesh m's primitive, or nullptr for kNoMaterial.
  const Material* material_of(uint32_t mesh) const {
    const uint32_t k = meshes[mesh].material;
    return k == kNoMaterial ? nullptr : &materials[k];
  }
};

// Mesh m of a scene read lazily (Scene::mapped, its mesh released) with its arrays read back
// from the cache file, for the rare user of a whole mesh on the CPU (scene_export).
// Throws std::runtime_error naming the file for an unreadable file or an index out of range.
Mesh read_mapped_mesh(const Scene& scene, uint32_t m);

// Smooth per-vertex normals from area-weighted face normals (for meshes without NORMAL).
void compute_normals(Mesh& mesh);
// Zero-length normals (a file's normals may have them) would shade as NaN: replaces them by the
// computed smooth normal of their vertex.
void repair_normals(Mesh& mesh);

// Removes the triangles whose three positions are collinear (repeated indices, coincident or
// collinear vertices: an exactly zero cross product), or collinear at the precision of their float
// positions (their height over the longest edge at most 8 ulps of their largest coordinate: a
// 5 mm triangle 2 nm high, as exports have them), and returns how many. They cover no area, yet
// a GPU may rasterise a pixel of one after rounding its transformed vertices, with any depth
// (llvmpipe: the near plane's, metres in front of the triangle): no culling can foresee that
// pixel, so brute force and a culled frame would differ there. Real exports have such triangles.
uint64_t drop_zero_area_triangles(Mesh& mesh);

// Removes the triangles that repeat an earlier one of the mesh and returns how many: the same
// three positions (bit for bit) in the same winding, or in either winding where either_winding
// (the caller's material is double-sided: every face is drawn from both sides), whose corners
// draw alike (the same texture coordinates and colour, normals equal or opposite: the Shaded pass
// lights |n.l|). Exports make surfaces two-sided by repeating every face reversed on the same
// vertices (bim/schependomlaan: 86 k of 193 k triangles): drawn, each such pair costs twice and
// writes the same pixels; worse, smooth normals computed over the pair cancel to nothing. Call
// it before compute_normals, for opaque materials only (two layers of glass blend twice).
uint64_t drop_repeated_triangles(Mesh& mesh, bool either_winding);

// Prepares each mesh for drawing, deterministically: merges vertices equal in every attribute,
// reorders its triangles into spatial clusters of at most max_triangles triangles (recursive
// median split on triangle centroids) and fills Mesh::clusters (meshes at or under the threshold
// get one cluster), then orders each cluster's triangles for the vertex cache (meshoptimizer).
void split_mesh_clusters(Scene& scene, uint32_t max_triangles);

}  // namespace occ
