// Where cache files live and how they are written: the folder and name of a scene's cache, and
// the temporaries a writer renames into place (removed when their writer is gone). Used by the
// LOD cache (lod_cache.hpp) and the scene cache (scene_cache.hpp). No GL.
#pragma once
#include <cstddef>
#include <string>

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
// Live writers' files stay (processes that start together build a cache once: CacheBuildLock;
// writers that do not take it each write their own temporary, and the last rename wins). Returns how many it
// removed; errors are ignored (another process may remove the same file).
size_t remove_stale_cache_temps(const std::string& dir);
inline constexpr long kStaleTempSeconds = 3600;

// Held while a process builds a missing cache (an flock on PATH.lock, released when the process
// ends, however it ends): a process that finds the cache missing too waits for it, then reads
// what was built instead of building it again (processes that start together would otherwise
// each hold a whole scene and its LODs at once: 11 GB each at plant:200). Where the lock file
// cannot be made (a read-only folder) it locks nothing. Says on stderr, prefixed by `who`, when
// it waits.
class CacheBuildLock {
 public:
  CacheBuildLock(const std::string& path, const std::string& who);
  ~CacheBuildLock();
  CacheBuildLock(const CacheBuildLock&) = delete;
  CacheBuildLock& operator=(const CacheBuildLock&) = delete;

 private:
  int fd_ = -1;
};

}  // namespace occ
