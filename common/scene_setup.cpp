#include "common/scene_setup.hpp"

#include <chrono>
#include <cstdio>
#include <iostream>

#include "common/hash.hpp"
#include "common/scene_io.hpp"

namespace occ {

void add_scene_options(Cli& cli, SceneOptions& o) {
  cli.option("scene", &o.spec, "SPEC",
             "scene: file.gltf|file.glb, city[:BXxBZ[:N[:F[:D]]]] (generated), plant:M (M million triangles, "
             "unique meshes), layout:NXxNZ:file");
  cli.option("arity", &o.build.arity, 2, 64, "hierarchy: max children per node");
  cli.option("leaf-items", &o.build.leaf_items, 1, 1024, "hierarchy: max items per leaf");
  cli.option("cluster-triangles", &o.build.cluster_triangles, 16, 1 << 24,
             "hierarchy: meshes above this many triangles are split into spatial clusters");
  cli.option("lod-cache", &o.lod_cache, "DIR",
             "LOD/HLOD cache folder (default $XDG_CACHE_HOME/occswitch or ~/.cache/occswitch)");
}

LoadedScene load_and_build(const SceneOptions& opts, const std::string& who, bool with_lod) {
  auto t0 = std::chrono::steady_clock::now();
  LoadedScene ls{load_scene(opts.spec), {}};
  auto t1 = std::chrono::steady_clock::now();
  ls.hierarchy = Hierarchy::build(ls.scene, opts.build);
  auto t2 = std::chrono::steady_clock::now();
  auto ms = [](auto a, auto b) { return std::chrono::duration<double, std::milli>(b - a).count(); };
  char buf[512];
  std::snprintf(buf, sizeof buf,
                "%s: scene %s: %zu objects, %zu meshes, %.3f M triangles, %zu items, %zu nodes, depth %u, "
                "fingerprint %016llx (load %.0f ms, build %.0f ms)",
                who.c_str(), opts.spec.c_str(), ls.scene.objects.size(), ls.scene.meshes.size(),
                ls.scene.triangle_count() / 1e6, ls.hierarchy.items().size(), ls.hierarchy.size(),
                ls.hierarchy.depth(), static_cast<unsigned long long>(ls.hierarchy.fingerprint()), ms(t0, t1),
                ms(t1, t2));
  std::cerr << buf << "\n";
  ls.fingerprint = ls.hierarchy.fingerprint();
  if (with_lod) {
    ls.lod = std::make_unique<LodData>(
        load_or_build_lod(ls.scene, ls.hierarchy, opts.lod, opts.lod_cache, opts.spec, who));
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
