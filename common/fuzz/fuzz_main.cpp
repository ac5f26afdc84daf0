// libFuzzer entry for one harness of fuzz_targets.hpp, chosen at build time (OCC_FUZZ_TARGET, the
// harness's name): common/fuzz/CMakeLists.txt builds gltf_fuzz, camera_path_fuzz, scene_cache_fuzz
// and lod_cache_fuzz from this file.
#include <cstdlib>

#include "common/fuzz/fuzz_targets.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const occ::fuzz::Target* const target = [] {
    const occ::fuzz::Target* t = occ::fuzz::find_target(OCC_FUZZ_TARGET);
    if (!t) std::abort();
    (void)occ::fuzz::fixture();  // built once, before the first input
    return t;
  }();
  (void)target->run({data, size});
  return 0;
}
