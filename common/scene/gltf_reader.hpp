// glTF 2.0 files (.gltf/.glb) as Scenes. Every failure throws InputError naming the file and the
// node/mesh/accessor at fault.
#pragma once
#include <string>

#include "common/scene/scene.hpp"

namespace occ {

// Loads all scenes' node trees (default scene if set, else scene 0) with node transforms and
// mesh instancing. Triangle primitives only (mode 4); other modes are counted and reported,
// not drawn. Zero-area triangles are left out, and triangles that repeat another of their
// opaque primitive (drop_repeated_triangles). A primitive without NORMAL is shaded flat, as glTF
// requires (Mesh::flat).
// Scene::files lists the file and every file it refers to that was read.
Scene load_gltf(const std::string& path);

// Bump whenever load_gltf's output for the same files changes: it keys the scene caches of
// glTF scenes (scene_cache.hpp), which are otherwise reused while their files are unchanged.
constexpr uint32_t kGltfReaderVersion = 3;  // 2: repeated triangles left out; 3: flat

// Whether path names a glTF file: it ends in .gltf or .glb, in any case.
bool is_gltf_path(const std::string& path);

}  // namespace occ
