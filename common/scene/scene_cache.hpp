// The scene cache: a generated scene and its hierarchy, preprocessed once, so the next start of
// a big `plant:M` reads them instead of generating and building them again in every process.
// One file per (scene spec, hierarchy parameters) beside the LOD cache (lod_cache.hpp: same
// folder, `.scene` instead of `.lod`); the LODs stay in their own cache, keyed by the hierarchy
// fingerprint this one restores.
//
// Format: a header (magic "OCCSCN\r\n", format version, cache key, payload bytes, payload
// StreamHash) and the payload: first the structure, the Scene (source, each mesh's name,
// clusters, material and the counts of its arrays, objects, materials, textures, images) and the
// Hierarchy (parameters, depth, fingerprint, nodes, items); then the array section, every
// mesh's vertex and index arrays one after the other, in mesh order. Arrays are copied in host
// byte order. A lazy start reads the structure only: one short read, however big the scene. Written atomically (temporary file + rename), streamed (never
// the whole payload in memory). Read from a memory mapping, every size checked before it is
// trusted, the parsed pages dropped as it goes (mapped_file.hpp). No GL.
//
// `plant:` specs, glTF and other model files (model_reader.hpp) are cached: the other generated
// scenes are instanced and load in well under a second. The key covers the spec (a file's
// canonical path too), the hierarchy parameters, --up, the cache format, plant::kGeneratorVersion,
// kGltfReaderVersion and kModelReaderVersion (bump them when the generator's or a reader's output
// changes). The structure also lists the files a file's scene was read from (Scene::files: path, size, modification time): a file that changed or is
// gone makes the cache stale.
#pragma once
#include <optional>
#include <string>

#include "common/scene/hierarchy.hpp"
#include "common/scene/scene.hpp"
#include "common/scene/scene_io.hpp"

namespace occ {

struct CachedScene {
  Scene scene;
  Hierarchy hierarchy;
};

// Whether `spec` is one the scene cache stores.
bool scene_cache_applies(const std::string& spec);
// DIR/<scene name>-<hash of spec>.scene (DIR as for lod_cache_path).
std::string scene_cache_path(const std::string& cache_dir, const std::string& spec);
// `up` (--up) is part of the key: the cache holds the scene turned.
uint64_t scene_cache_key(const std::string& spec, const BuildParams& params, UpAxis up = UpAxis::Y);

// Writes atomically; returns an error message or nullopt. The scene's geometry must not be
// released.
std::optional<std::string> save_scene_cache(const std::string& path, uint64_t key, const Scene& scene,
                                            const Hierarchy& h);
// nullopt and *why (missing, truncated, bad magic, version, stale key, checksum, inconsistent
// data, with what and where) when the file cannot be used. First removes the stale temporaries
// of its folder (remove_stale_cache_temps, cache_files.hpp). Read lazily where the meshes'
// arrays take more than lazy_above_bytes (scene_array_bytes; UINT64_MAX: never): they stay in
// the file (Scene::mapped; the meshes come released, with their counts, clusters and boxes),
// what a process under --geometry-budget streams from. Then the payload's checksum is not
// checked (it would read the whole file at every start: 6 GB at plant:200); the structure is,
// every count and range as always, and each mesh's indices when the upload reads it.
std::optional<CachedScene> load_scene_cache(const std::string& path, uint64_t key, std::string* why,
                                            uint64_t lazy_above_bytes = UINT64_MAX);
// The bytes of the scene's vertex and index arrays (the cache's array section).
uint64_t scene_array_bytes(const Scene& s);

}  // namespace occ
