// The LOD cache file: where it lives and load-or-build. The format (lod_cache.cpp): a header
// (magic "OCCLOD\r\n", format version, LodData::cache_key, payload bytes, payload hash) and the
// payload (every LodMesh and table of LodData, copied in host byte order; its hash is
// LodData::hash()). LodData::save/load write and read it (lod_data.hpp). No GL.
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
