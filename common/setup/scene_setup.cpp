#include "common/setup/scene_setup.hpp"

#include <malloc.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <chrono>
#include <cstdlib>
#include <cstdio>
#include <filesystem>
#include <optional>
#include <iostream>

#include "common/cache_files.hpp"
#include "common/error.hpp"
#include "common/hash.hpp"
#include "common/progress.hpp"
#include "common/scene/gltf_reader.hpp"
#include "common/scene/scene_cache.hpp"
#include "common/scene/scene_io.hpp"

namespace occ {

void add_scene_options(Cli& cli, SceneOptions& o) {
  cli.group(CliGroup::scene);
  cli.option("scene", &o.spec, "SPEC",
             "scene: file.gltf|file.glb, a model file (.ply .obj .stl .fbx .dae .3ds .off ...), city[:BXxBZ[:N[:F[:D]]]] (generated), plant:M (M million triangles, "
             "unique meshes), layout:NXxNZ:file, bridge[:N], office[:N], pipes[:N] (structures: N spans, bays, "
             "modules), hard:KIND[:N] (hard cases)");
  cli.choice<UpAxis>("up", &o.up, {{"y", UpAxis::Y}, {"z", UpAxis::Z}},
                     "the axis the scene's data points up: y (glTF), z (CAD tools, scans): turned to y");
  cli.option("lod-cache", &o.lod_cache, "DIR",
             "LOD/HLOD and scene cache folder: plant:M, glTF and model file scenes and their hierarchy are kept "
             "there in binary (a file's rebuilt when any of its files changed) (default $XDG_CACHE_HOME/occswitch "
             "or ~/.cache/occswitch)");
  cli.option("geometry-budget", &o.geometry_budget, "MB|auto|all",
             "GPU memory for geometry: scenes with a scene cache stream their meshes and LODs from it within MB "
             "(plant:M always, a glTF where larger), the least recently drawn evicted; other scenes stream from "
             "their CPU copy where they are larger; auto = a 24th of the machine's memory (at least 256); all = everything uploaded at start");
}

uint64_t geometry_budget_bytes(const SceneOptions& o) {
  const std::string& v = o.geometry_budget;
  if (v == "all") return 0;
  if (v == "auto") {
    const uint64_t phys = uint64_t(::sysconf(_SC_PHYS_PAGES)) * uint64_t(::sysconf(_SC_PAGESIZE));
    return std::max<uint64_t>(phys / 24, uint64_t(256) << 20);
  }
  char* end = nullptr;
  errno = 0;
  const unsigned long long mb = std::strtoull(v.c_str(), &end, 10);
  if (v.empty() || !std::isdigit(static_cast<unsigned char>(v[0])) || *end != '\0' || errno || mb < 1 ||
      mb > (uint64_t(1) << 30))
    throw InputError("--geometry-budget: expected a number of MB (1 or more), auto or all, got '" + v + "'");
  return uint64_t(mb) << 20;
}

namespace {

// The LOD data for a loaded scene: from the LOD cache, or built and saved. For a scene read
// lazily (Scene::mapped) the LODs are read lazily too; building them needs the geometry, so then
// the scene cache is read whole for the build, and the saved LOD cache is read back lazily.
LodData load_lod(const SceneOptions& opts, const LoadedScene& ls, const std::string& scene_cache,
                 uint64_t scene_key, const std::string& who) {
  if (!ls.scene.mapped) return load_or_build_lod(ls.scene, ls.hierarchy, opts.lod, opts.lod_cache, opts.spec, who);
  const std::string path = lod_cache_path(opts.lod_cache, opts.spec);
  const uint64_t key = LodData::cache_key(ls.hierarchy, opts.lod);
  std::string why;
  auto read_lazily = [&]() -> std::optional<LodData> {
    const double t0 = now_ms();
    std::optional<LodData> d = LodData::load(path, key, ls.scene, ls.hierarchy, &why, true);
    if (d) {
      char buf[512];
      std::snprintf(buf, sizeof buf, "%s: LOD cache %s: %zu HLODs, %.3f M LOD triangles (read in %.0f ms; their "
                    "arrays stay in the mapped file, streamed as frames need them)", who.c_str(), path.c_str(),
                    d->hlods().size(), d->total_triangles() / 1e6, now_ms() - t0);
      std::cerr << buf << "\n";
    }
    return d;
  };
  if (auto d = read_lazily()) return std::move(*d);
  { CacheBuildLock wait(path, who); }  // another process may be building it: wait for that
  if (auto d = read_lazily()) return std::move(*d);
  if (why != "missing") std::cerr << who << ": LOD cache " << path << " is unusable (" << why << "): rebuilding\n";
  {
    std::optional<CachedScene> whole = load_scene_cache(scene_cache, scene_key, &why);
    if (!whole) throw InputError("scene cache " + scene_cache + " became unusable: " + why);
    load_or_build_lod(whole->scene, whole->hierarchy, opts.lod, opts.lod_cache, opts.spec, who);
  }
  ::malloc_trim(0);  // the whole scene and the built LODs leave the process
  if (auto d = read_lazily()) return std::move(*d);
  throw InputError("LOD cache " + path + " cannot be read back after it was built: " + why);
}

}  // namespace

LoadedScene load_and_build(const SceneOptions& opts, const std::string& who, bool with_lod) {
  auto t0 = std::chrono::steady_clock::now();
  LoadedScene ls;
  auto ms = [](auto a, auto b) { return std::chrono::duration<double, std::milli>(b - a).count(); };
  char buf[768];
  const bool use_cache = scene_cache_applies(opts.spec);
  // Read lazily (the arrays left in the cache, streamed within the budget): a plant always under
  // a budget (its start reads the structure only), a glTF or model file's scene where its arrays
  // exceed it (else it is read whole, as fast, and the switch nodes can look for sealed objects in it).
  const uint64_t budget = geometry_budget_bytes(opts);
  const bool file = use_cache && opts.spec.rfind("plant:", 0) != 0;
  const uint64_t lazy_above = budget == 0 ? UINT64_MAX : file ? budget : 0;
  const std::string cache_path = use_cache ? scene_cache_path(opts.lod_cache, opts.spec) : "";
  const uint64_t cache_key = use_cache ? scene_cache_key(opts.spec, opts.build, opts.up) : 0;
  std::optional<CachedScene> cached;
  std::optional<CacheBuildLock> building;  // held from a failed read to the written cache
  if (use_cache) {
    std::string why;
    cached = load_scene_cache(cache_path, cache_key, &why, lazy_above);
    if (!cached) {  // another process may be building it: wait for that, then read again
      building.emplace(cache_path, who);
      cached = load_scene_cache(cache_path, cache_key, &why, lazy_above);
    }
    if (!cached && why != "missing")
      std::cerr << who << ": scene cache " << cache_path << " is unusable (" << why << "): rebuilding it\n";
  }
  auto t1 = t0, t2 = t0;
  const bool from_cache = cached.has_value();
  if (from_cache) {
    ls.scene = std::move(cached->scene);
    ls.hierarchy = std::move(cached->hierarchy);
    cached.reset();
    t1 = t2 = std::chrono::steady_clock::now();
  } else {
    ls.scene = load_scene(opts.spec);
    apply_up_axis(ls.scene, opts.up);
    t1 = std::chrono::steady_clock::now();
    ls.hierarchy = Hierarchy::build(ls.scene, opts.build);
    t2 = std::chrono::steady_clock::now();
  }
  std::snprintf(buf, sizeof buf,
                "%s: scene %s: %zu objects, %zu meshes, %.3f M triangles, %zu items, %zu nodes, depth %u, "
                "fingerprint %016llx (%s %.0f ms, build %.0f ms)",
                who.c_str(), opts.spec.c_str(), ls.scene.objects.size(), ls.scene.meshes.size(),
                ls.scene.triangle_count() / 1e6, ls.hierarchy.items().size(), ls.hierarchy.size(),
                ls.hierarchy.depth(), static_cast<unsigned long long>(ls.hierarchy.fingerprint()),
                from_cache ? ("read from scene cache " + cache_path + " in").c_str() : "load", ms(t0, t1),
                ms(t1, t2));
  std::cerr << buf << "\n";
  if (ls.scene.zero_area_triangles > 0)
    std::cerr << who << ": " << ls.scene.zero_area_triangles
              << " zero-area triangles of the file left out (collinear vertices, exactly or at float precision: nothing to draw)\n";
  if (ls.scene.repeated_triangles > 0)
    std::cerr << who << ": " << ls.scene.repeated_triangles
              << " repeated triangles of the file left out (the same positions and look as another of their mesh, in"
                 " either winding where double-sided)\n";
  if (use_cache && !from_cache) {
    const auto t3 = std::chrono::steady_clock::now();
    if (auto err = save_scene_cache(cache_path, cache_key, ls.scene, ls.hierarchy)) {
      std::cerr << who << ": warning: scene cache not written: " << *err << "\n";
    } else {
      std::error_code ec;
      const auto bytes = std::filesystem::file_size(cache_path, ec);
      std::snprintf(buf, sizeof buf, "%s: wrote scene cache %s (%.1f MB in %.0f ms)", who.c_str(), cache_path.c_str(),
                    ec ? 0.0 : double(bytes) / 1e6, ms(t3, std::chrono::steady_clock::now()));
      std::cerr << buf << "\n";
    }
  }
  building.reset();
  if (use_cache && !from_cache && scene_array_bytes(ls.scene) > lazy_above) {
    // built now: read back lazily, so the built copy leaves memory
    std::string why;
    std::optional<CachedScene> back = load_scene_cache(cache_path, cache_key, &why, lazy_above);
    if (back) {
      ls.scene = std::move(back->scene);
      ls.hierarchy = std::move(back->hierarchy);
    }
    ::malloc_trim(0);  // the heap gives the built scene's pages back
  }
  ls.fingerprint = ls.hierarchy.fingerprint();
  if (with_lod) {
    ls.lod = std::make_unique<LodData>(load_lod(opts, ls, cache_path, cache_key, who));
    Hasher fh;
    fh.u64(ls.hierarchy.fingerprint());
    fh.u64(ls.lod->hash());
    ls.fingerprint = fh.value();
    // Pay only for what the scene calls for: LODs that save (almost) nothing are dropped, so no
    // process selects, uploads or draws them. Every process decides from the same data (its hash
    // is in the fingerprint), so the three agree.
    const LodBenefit benefit = lod_benefit(*ls.lod, ls.hierarchy);
    std::snprintf(buf, sizeof buf,
                  "%s: scene fingerprint with LODs %016llx; the coarsest LODs save %.1f %% of the triangles (%llu)",
                  who.c_str(), static_cast<unsigned long long>(ls.fingerprint), 100.0 * benefit.fraction,
                  static_cast<unsigned long long>(benefit.saved_triangles));
    std::cerr << buf << "\n";
    if (!benefit.worth_selecting()) {
      std::snprintf(buf, sizeof buf,
                    "%s: LOD selection skipped: LODs that save less than %.0f %% or %llu triangles are not worth "
                    "selecting; drawing full detail as with --pixel-error 0",
                    who.c_str(), 100.0 * LodBenefit::kMinFraction,
                    static_cast<unsigned long long>(LodBenefit::kMinSavedTriangles));
      std::cerr << buf << "\n";
      ls.lod.reset();
    } else if (const uint32_t n = forbid_blended_hlods(*ls.lod, ls.scene, ls.hierarchy)) {
      std::cerr << who << ": " << n << " HLODs not used: their subtrees hold BLEND (transparent) objects, "
                << "which an HLOD would draw opaque\n";
    }
  }
  return ls;
}

}  // namespace occ
