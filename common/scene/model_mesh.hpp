// What the readers of other model formats (ply_reader, assimp_reader) share: the last steps that
// make a mesh of theirs drawable the way glTF's are, and their file-name tests. No GL.
#pragma once
#include <cstdint>
#include <string>
#include <string_view>

#include "common/scene/scene.hpp"

namespace occ {

// Whether path ends in suffix (lower case, with its dot), in any case.
bool has_extension_ci(const std::string& path, std::string_view suffix);

// The triangles add_model_mesh left out, and the mesh's index in Scene::meshes (-1: none left).
struct ModelMeshCounts {
  int64_t mesh = -1;
  uint64_t zero_area = 0, repeated = 0;
};

// Adds `m` (positions and indices read, normals when has_normals, its material set: kNoMaterial or
// an index into s.materials) to s.meshes as glTF's reader does: zero-area triangles left out,
// then repeated ones for an opaque material (in either winding where it is double-sided, as
// kNoMaterial is), zero normals repaired, or smooth normals computed and the mesh shaded flat
// when the file has none. A mesh left without triangles is not added.
ModelMeshCounts add_model_mesh(Scene& s, Mesh m, bool has_normals);

// The material of a mesh whose colours are its vertices': white, opaque, double-sided (the file
// says nothing of its sides). Added to s.materials the first time; its index.
uint32_t vertex_colour_material(Scene& s);

}  // namespace occ
