#include "common/cull/backend_choice.hpp"

#include <sstream>

#include "common/error.hpp"

namespace occ {

namespace {
std::string tau_words(double tau) {
  std::ostringstream s;
  s << "tau " << tau;
  return s.str();
}
}  // namespace

const std::vector<std::pair<std::string, std::optional<BackendKind>>>& backend_words() {
  static const std::vector<std::pair<std::string, std::optional<BackendKind>>> words = {
      {"auto", std::nullopt},
      {"cpu", BackendKind::cpu},
      {"queries", BackendKind::queries},
      {"gpu-pyramid", BackendKind::gpu_pyramid},
      {"cpu-pyramid", BackendKind::cpu_pyramid}};
  return words;
}

const char* backend_name(BackendKind k) {
  for (const auto& [word, kind] : backend_words())
    if (kind == k) return word.c_str();
  return "?";
}

BackendChoice choose_backend(const BackendInputs& in, std::optional<bool> adaptive_queries,
                             std::optional<int> visibility_hold) {
  BackendChoice c;
  const bool pixel_lod = in.visible_pixel_lod && in.tau > 0;
  if (in.flag) {
    c.kind = *in.flag;
    c.why = std::string("--backend ") + backend_name(c.kind);
    if (c.kind == BackendKind::cpu && pixel_lod)
      throw InputError("--backend cpu: --visible-pixel-lod needs sample counts, which the CPU back end's tests do not give");
    if (c.kind == BackendKind::cpu && !in.triangles_in_memory)
      throw InputError("--backend cpu: the scene's triangles are not in memory (streamed within --geometry-budget)");
  } else if (!in.software_renderer) {
    c.kind = BackendKind::queries;
    c.why = "auto: hardware renderer " + in.renderer;
  } else {
    // The CPU raster draws renderables at full detail only: at tau > 0 the renderer's depth
    // holds the chosen levels and the CPU's would not.
    const bool cpu = in.tau == 0 && in.triangles_in_memory;
    c.kind = cpu ? BackendKind::cpu : BackendKind::cpu_pyramid;
    c.why = "auto: software renderer " + in.renderer + ", " + tau_words(in.tau);
    if (!in.triangles_in_memory) c.why += ", triangles streamed";
  }
  const bool cheap_tests = c.kind == BackendKind::cpu;
  c.adaptive_queries = adaptive_queries.value_or(!cheap_tests);
  c.visibility_hold = visibility_hold.value_or(cheap_tests ? 0 : kAutoVisibilityHold);
  return c;
}

std::string backend_line(const BackendChoice& c) {
  return std::string("occlusion back end: ") + backend_name(c.kind) + " (" + c.why + "; adaptive queries " +
         (c.adaptive_queries ? "on" : "off") + ", visibility hold " + std::to_string(c.visibility_hold) + ")";
}

}  // namespace occ
