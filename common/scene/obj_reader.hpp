// Wavefront OBJ files (+ their MTL materials) as Scenes, through tinyobjloader (Debian's
// libtinyobjloader: faster and leaner than Assimp's OBJ reader on big files, docs/formats.md). Every failure throws InputError naming the file and what is wrong.
#pragma once
#include <string>

#include "common/scene/scene.hpp"

namespace occ {

// Each `o`/`g` group (tinyobjloader's shape) becomes an object with the identity transform, one
// mesh per material it uses. Polygons are split into triangles; lines and points are counted and
// reported, not drawn. Materials: Kd (diffuse) as the base colour, d (dissolve) as its alpha
// (below 1: BLEND), map_Kd decoded to RGBA8 (texture coordinates flipped to glTF's top-left
// origin); lit (illum is not read: tinyobjloader gives 0 where the MTL has none); single-sided, as OBJ says nothing of sides (as Assimp reads it). Faces
// without a material get the per-object colour of generated scenes (kNoMaterial, double-sided).
// A mesh without normals is shaded flat (Mesh::flat). Zero-area and repeated triangles are left
// out as glTF's are. Scene::files lists the OBJ, its MTL files and textures.
// Rejected: what tinyobjloader cannot read, an index out of range, a face of fewer than three
// vertices (a line cut short: a truncated file), a file with no triangles, a texture that cannot
// be loaded.
Scene load_obj(const std::string& path);

}  // namespace occ
