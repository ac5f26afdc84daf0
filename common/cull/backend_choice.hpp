// Which occlusion back end a switch node uses (common/cull/occlusion_backend.hpp), chosen once at
// start by choose_backend() from what the process knows then: the renderer's class, tau and
// visible-pixel LOD, whether the scene's triangles are in memory, and the user's --backend.
#pragma once
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace occ {

enum class BackendKind {
  cpu,          // depth rasterised on the CPU, boxes and leaves tested against it (CpuBackend)
  queries,      // the renderer's depth, one occlusion query a box
  gpu_pyramid,  // the renderer's depth, a depth pyramid built on the GPU first, queries for the rest
  cpu_pyramid,  // the renderer's depth read back once a frame into a pyramid, the rest counted in batch draws
};

// The --backend words, "auto" (nullopt) first.
const std::vector<std::pair<std::string, std::optional<BackendKind>>>& backend_words();
const char* backend_name(BackendKind k);  // "cpu", "queries", "gpu-pyramid", "cpu-pyramid"

struct BackendInputs {
  std::optional<BackendKind> flag;  // --backend (nullopt: auto)
  bool software_renderer = true;    // the renderer rasterises on the CPU (llvmpipe ...)
  std::string renderer;             // its name, for the start-up line
  double tau = 0;                   // pixels of LOD error (0: full detail)
  bool visible_pixel_lod = false;   // needs sample counts from the tests
  bool triangles_in_memory = true;  // false: streamed within a geometry budget, not on the CPU
};

// The visibility hold's frames where a test is dear (every back end but cpu), at auto.
constexpr int kAutoVisibilityHold = 2;

struct BackendChoice {
  BackendKind kind = BackendKind::queries;
  std::string why;  // "auto: software renderer llvmpipe, tau 0" or "--backend queries"
  // The auto settings that come with the back end: saving a test pays where a test is dear
  // (an occlusion query or box draw), not where a test is a CPU pyramid probe and a few faces.
  bool adaptive_queries = true;
  int visibility_hold = 0;
};

// The one choice. auto: cpu on a software renderer at tau 0 with the triangles in memory,
// cpu-pyramid elsewhere on a software renderer, queries on a hardware GPU. A forced cpu that
// cannot work (visible-pixel LOD needs sample counts; a streamed scene has no triangles on the
// CPU) throws InputError naming --backend and why. `adaptive_queries` / `visibility_hold`: the
// user's (nullopt: the back end's default).
BackendChoice choose_backend(const BackendInputs& in, std::optional<bool> adaptive_queries,
                             std::optional<int> visibility_hold);

// The one start-up line: "occlusion back end: cpu (auto: ...; adaptive queries off, visibility hold 0)".
std::string backend_line(const BackendChoice& c);

}  // namespace occ
