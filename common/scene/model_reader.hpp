// Model files other than glTF: which reader reads which file, and the version that keys their
// scene caches.
//   ply_reader.hpp     load_ply: PLY (ASCII, binary), our own reader, fast on big scans
//   obj_reader.hpp     load_obj: OBJ + MTL through tinyobjloader, fast on big files
//   assimp_reader.hpp  load_with_assimp: OBJ, STL, FBX, COLLADA (.dae), 3DS, OFF and the rest
//                      of what Debian's Assimp reads
#pragma once
#include <cstdint>
#include <string>

#include "common/scene/scene.hpp"

namespace occ {

// Whether path names a model file these readers take (by its extension, in any case): .ply, or
// one Assimp reads; glTF files are gltf_reader's.
bool is_model_path(const std::string& path);

// The file read by its reader: load_ply for .ply, load_obj for .obj, load_with_assimp for the rest. Throws
// InputError naming the file and what is wrong.
Scene load_model(const std::string& path);

// Bump whenever load_model's output for the same files changes: it keys the scene caches of model
// files (scene_cache.hpp), which are otherwise reused while their files are unchanged.
constexpr uint32_t kModelReaderVersion = 2;  // 2: big meshes in spatial parts

}  // namespace occ
