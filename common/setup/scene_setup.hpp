// The scene every process builds identically: --scene spec + hierarchy build parameters.
// Shared by render_client, switch_node and the tools so flags and messages are the same.
#pragma once
#include <memory>
#include <string>

#include "common/cli.hpp"
#include "common/scene/hierarchy.hpp"
#include "common/lod/lod.hpp"
#include "common/scene/scene.hpp"
#include "common/scene/scene_io.hpp"

namespace occ {

struct SceneOptions {
  std::string spec = "city";
  BuildParams build;
  LodParams lod;
  std::string lod_cache;  // --lod-cache DIR ("" = the default cache folder, see lod_cache.hpp)
  UpAxis up = UpAxis::Y;    // --up y|z: the axis the scene's data points up (apply_up_axis)
  std::string geometry_budget = "auto";  // --geometry-budget MB|auto|all (geometry_budget_bytes)
};

void add_scene_options(Cli& cli, SceneOptions& opts);

// The GPU geometry budget of --geometry-budget in bytes: MB (at least 1), auto (a 24th of the
// machine's memory, at least 256 MiB), or 0 for all (every mesh resident from the start, read
// whole before the upload). Throws InputError naming the flag for anything else.
uint64_t geometry_budget_bytes(const SceneOptions& opts);

struct LoadedScene {
  Scene scene;
  Hierarchy hierarchy;
  std::unique_ptr<LodData> lod;  // null unless requested (tau > 0) and worth it (lod_benefit)
  // What Hello carries: the hierarchy fingerprint, combined with LodData::hash() when LODs are
  // loaded (the LOD cache is part of the scene's identity).
  uint64_t fingerprint = 0;
};

// With a budget (geometry_budget_bytes > 0) a scene that has a scene cache is read lazily (a
// plant:M always, a glTF or model file's scene where its arrays are larger than the budget): its
// meshes' and LODs' arrays stay in the mapped caches (Scene::mapped, LodData::mapped) and are
// streamed to the GPU as frames need them; a cache built now is written first, then read so.
// Loads/generates the scene and builds the hierarchy, or reads both from the scene cache
// (scene_cache.hpp: plant:M specs and glTF files; a missing, stale or unusable cache is rebuilt and rewritten,
// saying why); prints one summary line to stderr
// prefixed by `who` ("scene: city: 6400 objects, 2.1M triangles, ..."). With `with_lod`, also
// loads the LOD cache or builds it (progress bar on a terminal, a summary line). Throws InputError.
LoadedScene load_and_build(const SceneOptions& opts, const std::string& who, bool with_lod = false);

}  // namespace occ
