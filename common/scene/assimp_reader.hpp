// Model files read through Assimp (Debian's libassimp: STL, FBX, COLLADA, 3DS, OFF and the rest of
// what it reads; load_model gives it neither PLY nor OBJ, which have faster readers, but it reads
// them too, as write_model's side-by-side measurement does) as Scenes. Every failure throws InputError naming the file and, where
// known, the mesh, node or material at fault.
#pragma once
#include <string>

#include "common/scene/scene.hpp"

namespace occ {

// The file's node tree with its transforms (double precision; each node's meshes become objects,
// a mesh placed by several nodes is instanced). Triangles only: polygons are triangulated, meshes
// of points or lines are counted and reported, not drawn. Per mesh material: base colour (the PBR
// base colour, else the diffuse colour) times opacity (below 1: BLEND), the base colour or diffuse
// texture (a file beside the model or an embedded image, decoded to RGBA8; texture coordinates
// with (0,0) at the image's top-left texel, as glTF's), two-sided (the file's flag; absent: single-
// sided, as Assimp defines it), unlit for the no-shading models. A mesh with Assimp's default
// material (the file has none) gets the per-object colour of generated scenes (kNoMaterial,
// double-sided), or the vertex colour material where it has vertex colours. A mesh without
// normals is shaded flat (Mesh::flat). Zero-area and repeated triangles are left out as glTF's
// are. Scene::files lists the file and every file Assimp opened for it (an OBJ's MTL, textures).
// Rejected: what Assimp cannot read (its message is kept), a file with no triangles, a value or
// transform that is not finite, a texture that cannot be loaded.
Scene load_with_assimp(const std::string& path);

// Whether Assimp reads files with path's extension (glTF excepted: gltf_reader reads those).
bool assimp_reads(const std::string& path);

}  // namespace occ
