// What the readers of other model formats (ply_reader, assimp_reader) share: the last steps that
// make a mesh of theirs drawable the way glTF's are, and their file-name tests. No GL.
#pragma once
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "common/scene/scene.hpp"

namespace occ {

// Whether path ends in suffix (lower case, with its dot), in any case.
bool has_extension_ci(const std::string& path, std::string_view suffix);

// The triangles add_model_mesh left out, and the indices in Scene::meshes of the meshes it added
// (none when no triangle was left).
struct ModelMeshCounts {
  std::vector<uint32_t> meshes;
  uint64_t zero_area = 0, repeated = 0;
};

// A file's mesh of more triangles than this is added as several meshes of at most this many
// (spatial parts): the geometry budget streams whole meshes, so a scan of one mesh of millions of
// triangles streams in parts that fit a budget.
constexpr size_t kMaxModelMeshTriangles = size_t(1) << 20;

// Adds `m` (positions and indices read, normals when has_normals, its material set: kNoMaterial or
// an index into s.materials) to s.meshes as glTF's reader does: zero-area triangles left out,
// then repeated ones for an opaque material (in either winding where it is double-sided, as
// kNoMaterial is), zero normals repaired, or smooth normals computed and the mesh shaded flat
// when the file has none; then split into spatial parts of at most kMaxModelMeshTriangles
// (recursive median splits of the triangles' centroids along the longest axis; each part keeps
// its triangles in file order and the vertices they use). A mesh left without triangles is not
// added. Deterministic.
ModelMeshCounts add_model_mesh(Scene& s, Mesh m, bool has_normals);

// The material of a mesh whose colours are its vertices': white, opaque, double-sided (the file
// says nothing of its sides). Added to s.materials the first time; its index.
uint32_t vertex_colour_material(Scene& s);

}  // namespace occ
