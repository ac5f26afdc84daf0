// The LOD cache file: where it lives and load-or-build. The format (lod_cache.cpp): a header
// (magic "OCCLOD\r\n", format version, LodData::cache_key, payload bytes, payload hash) and the
// payload (every LodMesh and table of LodData, copied in host byte order; its hash is
// LodData::hash()). LodData::save/load write and read it (lod_data.hpp). No GL.
#pragma once
#include <string>

#include "common/hierarchy.hpp"
#include "common/lod_data.hpp"
#include "common/scene.hpp"

namespace occ {

// Where the cache of a scene lives: DIR/<scene name>-<hash of spec>.lod; DIR = --lod-cache or
// $XDG_CACHE_HOME/occswitch or $HOME/.cache/occswitch or /tmp/occswitch.
std::string lod_cache_path(const std::string& cache_dir, const std::string& scene_spec);

// A cache file's temporary while a writer writes it: PATH.tmp.<host>.<pid namespace>.<pid>, the
// writer being this process or the one with `pid` (same host and namespace). Renamed to PATH when
// complete (atomic); a writer killed on the way leaves it behind.
std::string cache_temp_path(const std::string& path, long pid = -1);
// Removes the temporaries of cache files (*.lod.tmp.*, *.scene.tmp.*) in `dir` whose writer is
// gone: one of this host and pid namespace that no longer runs, or any (of another host on a
// shared disk, an older name, a pid taken by another process) untouched for kStaleTempSeconds.
// Live writers' files stay: processes that start together and build the same cache each write
// their own temporary, and the last rename wins (the contents are equal). Returns how many it
// removed; errors are ignored (another process may remove the same file).
size_t remove_stale_cache_temps(const std::string& dir);
inline constexpr long kStaleTempSeconds = 3600;

// Loads the cache or builds (and saves) the data, first removing the folder's stale temporaries.
// Prints what it did to stderr prefixed by `who`:
// a rebuild message for a stale or corrupt cache, and a one-line summary (time, memory, triangles).
LodData load_or_build_lod(const Scene& scene, const Hierarchy& h, const LodParams& params,
                          const std::string& cache_dir, const std::string& scene_spec, const std::string& who);

}  // namespace occ
