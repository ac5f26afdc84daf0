// The --scene spec parser (scene_io.hpp): splits a spec into its fields, checks its numbers and
// calls the scene source it names.
#include "common/scene/scene_io.hpp"

#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <glm/gtc/matrix_transform.hpp>
#include <optional>
#include <string_view>
#include <tuple>
#include <vector>

#include "common/cli.hpp"
#include "common/error.hpp"
#include "common/scene/model_reader.hpp"
#include "common/scene/plant.hpp"
#include "common/scene/structures.hpp"

namespace occ {
namespace {

// A decimal integer in [lo, hi]: the whole of `text`.
int parse_int(const std::string& spec, const char* what, std::string_view text, int lo, int hi) {
  int v = 0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
  if (ec != std::errc() || end != text.data() + text.size() || v < lo || v > hi)
    throw InputError("--scene '" + spec + "': " + what + " must be " + std::to_string(lo) + ".." +
                     std::to_string(hi) + " (got '" + std::string(text) + "')");
  return v;
}

// "AxB" with both in [1, hi].
std::pair<int, int> parse_dims(const std::string& spec, const char* what, std::string_view text, int hi) {
  const size_t x = text.find('x');
  if (x == std::string_view::npos)
    throw InputError("--scene '" + spec + "': " + what + " must be <X>x<Z>, e.g. 10x10 (got '" +
                     std::string(text) + "')");
  return {parse_int(spec, what, text.substr(0, x), 1, hi), parse_int(spec, what, text.substr(x + 1), 1, hi)};
}

// The fields of spec split at ':', at most max_fields; the last field keeps any further colons
// (layout paths).
std::vector<std::string_view> split_fields(const std::string& spec, size_t max_fields) {
  std::vector<std::string_view> f;
  std::string_view rest = spec;
  for (size_t c; f.size() + 1 < max_fields && (c = rest.find(':')) != std::string_view::npos;) {
    f.push_back(rest.substr(0, c));
    rest.remove_prefix(c + 1);
  }
  f.push_back(rest);
  return f;
}

// "DX,DY,DZ": three finite numbers with |v| <= 1e9.
glm::dvec3 parse_offset(const std::string& spec, std::string_view text) {
  glm::dvec3 d{};
  std::string_view rest = text;
  for (int axis = 0; axis < 3; ++axis) {
    const size_t comma = rest.find(',');
    if ((axis < 2) != (comma != std::string_view::npos))
      throw InputError("--scene '" + spec + "': offset must be DX,DY,DZ (got '" + std::string(text) + "')");
    const std::string component(rest.substr(0, comma));
    char* end = nullptr;
    errno = 0;
    const double v = component.empty() ? NAN : std::strtod(component.c_str(), &end);
    if (component.empty() || end != component.c_str() + component.size() || !std::isfinite(v) ||
        std::abs(v) > 1e9)
      throw InputError("--scene '" + spec + "': offset component '" + component +
                       "' must be a finite number with |v| <= 1e9");
    d[axis] = v;
    rest.remove_prefix(comma == std::string_view::npos ? rest.size() : comma + 1);
  }
  return d;
}

// hard:<kind>[:N] (fields f of spec).
Scene hard_scene(const std::string& spec, const std::vector<std::string_view>& f) {
  const std::string_view kind = f[1];
  if (kind == "walls" && f.size() <= 3) return hard_walls(f.size() == 3 ? parse_int(spec, "walls", f[2], 1, 100) : 5);
  if (kind == "exit" && f.size() <= 3) return hard_exit(f.size() == 3 ? parse_int(spec, "field", f[2], 2, 100) : 16);
  if (kind == "span" && f.size() == 2) return hard_span();
  if (kind == "degenerate" && f.size() == 2) return hard_degenerate();
  if (kind == "cracks" && f.size() <= 3) return hard_cracks(f.size() == 3 ? parse_int(spec, "bays", f[2], 1, 50) : 6);
  throw InputError("--scene '" + spec +
                   "': unknown hard case; expected hard:walls[:N], hard:exit[:N], hard:span, hard:degenerate or "
                   "hard:cracks[:N]");
}

// bridge[:N], office[:N], pipes[:N] (structures.hpp), or nothing for another kind of spec.
std::optional<Scene> structure_scene(const std::string& spec) {
  struct Kind {
    const char* name;
    Scene (*make)(int);
    const char* count;
    int fallback, max;
  };
  static constexpr Kind kinds[] = {{"bridge", bridge, "spans", 16, 200},
                                   {"office", office, "bays", 16, 100},
                                   {"pipes", pipes, "modules", 24, 100}};
  const auto f = split_fields(spec, 3);
  for (const Kind& k : kinds) {
    if (f[0] != k.name) continue;
    if (f.size() > 2) throw InputError("--scene '" + spec + "': expected " + k.name + "[:N]");
    return k.make(f.size() == 2 ? parse_int(spec, k.count, f[1], 1, k.max) : k.fallback);
  }
  return std::nullopt;
}

}  // namespace

Scene load_scene(const std::string& spec) {
  auto split = [&](size_t max_fields) { return split_fields(spec, max_fields); };
  Scene scene;
  if (spec.rfind("offset:", 0) == 0) {
    const auto f = split(3);
    if (f.size() != 3 || f[2].empty())
      throw InputError("--scene '" + spec + "': expected offset:DX,DY,DZ:<scene spec>");
    const glm::dvec3 d = parse_offset(spec, f[1]);
    scene = load_scene(std::string(f[2]));
    const glm::dmat4 t = glm::translate(glm::dmat4(1.0), d);
    for (Object& o : scene.objects) o.transform = t * o.transform;
  } else if (spec.rfind("hard:", 0) == 0) {
    scene = hard_scene(spec, split(3));
  } else if (spec.rfind("layout:", 0) == 0) {
    const auto f = split(3);
    if (f.size() != 3 || f[2].empty())
      throw InputError("--scene '" + spec + "': expected layout:NXxNZ:path.gltf|.glb");
    const auto [nx, nz] = parse_dims(spec, "copies", f[1], kMaxLayoutCopies);
    scene = layout_grid(load_gltf(std::string(f[2])), nx, nz, 0.25);
  } else if (spec == "city" || spec.rfind("city:", 0) == 0) {
    const auto f = split(6);
    if (f.size() > 5) throw InputError("--scene '" + spec + "': expected city[:BXxBZ[:N[:F[:D]]]]");
    CityParams p;
    if (f.size() > 1) std::tie(p.blocks_x, p.blocks_z) = parse_dims(spec, "blocks", f[1], city::kMaxBlocks);
    if (f.size() > 2) p.buildings_per_block = parse_int(spec, "buildings per block", f[2], 1, city::kMaxBuildings);
    if (f.size() > 3) p.floors_max = parse_int(spec, "floors", f[3], 1, city::kMaxFloors);
    if (f.size() > 4) p.detail = parse_int(spec, "detail", f[4], 1, city::kMaxDetail);
    scene = generate_city(p);
  } else if (const std::optional<Scene> st = structure_scene(spec)) {
    scene = *st;
  } else if (spec.rfind("plant:", 0) == 0) {
    const std::string text = spec.substr(6);
    const std::optional<double> m = parse_finite(text);
    if (!m || !(*m >= plant::kMinMillions && *m <= plant::kMaxMillions))
      throw InputError("--scene '" + spec + "': millions of triangles must be a number in 0.01..200 (got '" + text +
                       "')");
    scene = plant::generate_plant(plant::PlantParams{*m, 1});
  } else if (is_gltf_path(spec)) {
    scene = load_gltf(spec);
  } else if (is_model_path(spec)) {
    scene = load_model(spec);
  } else {
    throw InputError("--scene '" + spec +
                     "': unknown scene; expected path.gltf, path.glb, a model file (.ply, .obj, .stl, .fbx, .dae, .3ds, .off, "
                     "...), city[:BXxBZ[:N[:F[:D]]]] "
                     "(blocks, buildings per block side, max floors, detail), layout:NXxNZ:path.gltf|.glb, "
                     "plant:M (M million triangles), hard:walls[:N], hard:exit[:N], hard:span, hard:degenerate, "
                     "hard:cracks[:N], bridge[:N], office[:N], pipes[:N] or offset:DX,DY,DZ:<spec>");
  }
  scene.source = spec;
  return scene;
}

void apply_up_axis(Scene& scene, UpAxis up) {
  if (up == UpAxis::Y) return;
  glm::dmat4 r(1.0);
  r[1] = glm::dvec4(0, 0, -1, 0);  // y -> -z
  r[2] = glm::dvec4(0, 1, 0, 0);   // z -> y
  for (Object& o : scene.objects) o.transform = r * o.transform;
}

}  // namespace occ
