// A host's start, for lod_temp_test: loads scene SPEC, builds its hierarchy and loads or builds
// (and writes) its LOD cache in DIR, as switch_node and render_client do; prints the LOD data's
// hash. Usage: lod_cache_writer DIR SPEC
#include <cstdio>

#include "common/error.hpp"
#include "common/lod/lod_cache.hpp"
#include "common/scene/scene_io.hpp"

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: lod_cache_writer DIR SPEC\n");
    return 2;
  }
  try {
    occ::Scene scene = occ::load_scene(argv[2]);
    const occ::Hierarchy h = occ::Hierarchy::build(scene, {});
    const occ::LodData lod = occ::load_or_build_lod(scene, h, {}, argv[1], argv[2], "writer");
    std::printf("%016llx\n", static_cast<unsigned long long>(lod.hash()));
  } catch (const occ::InputError& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
  return 0;
}
