// Fuzz harnesses for the readers of files other people make: glTF/GLB, PLY and OBJ scenes,
// camera-path CSVs, the binary scene and LOD caches, and the input messages of render_client
// --web's page. Each harness takes one input's bytes, hands them to
// the reader through its public entry (a file in a private temporary folder, as a host reads
// it), and checks the reader's contract:
//   - bad input is rejected with one non-empty error (InputError naming the file for glTF and
//     CSV; the `why` of the cache loaders), never another exception, a crash or a sanitizer report;
//   - what is accepted is usable: every index and size the data holds is in range (checked here
//     again, independently of the reader), and the next step a host takes on it runs.
// A violated property aborts (libFuzzer and the tests both see it as a crash).
//
// The cache harnesses take a whole cache file and rewrite its size and checksum fields before
// loading, with the key taken from the file: otherwise nearly every mutation stops at the
// checksum and the payload parser is never reached (the unmodified bytes are loaded first, for
// the header checks).
//
// Built two ways (common/fuzz/CMakeLists.txt): occ_fuzz_targets for the fixed-seed runs of the
// test suite (tests/fuzz_parsers_test.cpp), and one libFuzzer binary per harness (OCC_LIBFUZZER,
// clang, ASan+UBSan). Seeds: tests/fuzz/<name>/, written by tests/make_fuzz_seeds.cpp.
#pragma once
#include <cstdint>
#include <random>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "common/scene/hierarchy.hpp"
#include "common/scene/scene.hpp"

namespace occ::fuzz {

enum class Verdict { Accepted, Rejected };

struct Target {
  const char* name;  // gltf, camera_path, scene_cache, lod_cache, ply, obj, web_input (= its seed folder)
  Verdict (*run)(std::span<const uint8_t> input);
};

// The seven harnesses, and the one named `name` (nullptr when none is).
std::span<const Target> targets();
const Target* find_target(std::string_view name);

// The scene and hierarchy the LOD cache harness loads against (a cache only fits the hierarchy
// it was built for): hard:walls:1 split and built with kFixtureBuild. tests/make_fuzz_seeds.cpp
// writes the LOD cache seed from the same.
struct Fixture {
  Scene scene;
  Hierarchy hierarchy;
};
inline constexpr BuildParams kFixtureBuild{4, 1, 64};
const Fixture& fixture();

// One deterministic mutation of `b` (bit flips, bytes, truncation, junk, spliced text tokens and
// numbers, a chunk of `other`): the fixed-seed runs' mutator.
void mutate(std::vector<uint8_t>& b, const std::vector<uint8_t>& other, std::mt19937_64& rng);

// The files of a seed folder, in name order.
std::vector<std::vector<uint8_t>> read_seeds(const std::string& dir);

}  // namespace occ::fuzz
