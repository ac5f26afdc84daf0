// The LOD cache file: where it lives and load-or-build. The format (lod_cache.cpp): a header
// (magic "OCCLOD\r\n", format version, LodData::cache_key, payload bytes, payload hash) and the
// payload (its hash is LodData::hash()): first the structure (each cluster LOD's origin, error
// and array counts, the item slots, the same of each HLOD, the node and error tables), then the
// array section (every mesh's arrays one after the other, cluster LODs then HLODs), all copied
// in host byte order; a lazy start reads the structure only. LodData::save/load write and read
// it (lod_data.hpp). No GL.
#pragma once
#include <string>

#include "common/cache_files.hpp"
#include "common/scene/hierarchy.hpp"
#include "common/lod/lod_data.hpp"
#include "common/scene/scene.hpp"

namespace occ {


// Loads the cache or builds (and saves) the data, first removing the folder's stale temporaries.
// Prints what it did to stderr prefixed by `who`:
// a rebuild message for a stale or corrupt cache, and a one-line summary (time, memory, triangles).
LodData load_or_build_lod(const Scene& scene, const Hierarchy& h, const LodParams& params,
                          const std::string& cache_dir, const std::string& scene_spec, const std::string& who);

}  // namespace occ
