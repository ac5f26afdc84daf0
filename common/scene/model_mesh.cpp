// The shared last steps of the model readers (model_mesh.hpp).
#include "common/scene/model_mesh.hpp"

#include <cctype>

namespace occ {

bool has_extension_ci(const std::string& path, std::string_view suffix) {
  if (path.size() < suffix.size()) return false;
  for (size_t i = 0; i < suffix.size(); ++i)
    if (std::tolower(static_cast<unsigned char>(path[path.size() - suffix.size() + i])) != suffix[i]) return false;
  return true;
}

ModelMeshCounts add_model_mesh(Scene& s, Mesh m, bool has_normals) {
  ModelMeshCounts c;
  if (!has_normals) m.normals.clear();
  c.zero_area = drop_zero_area_triangles(m);
  if (m.indices.empty()) return c;
  const Material* mat = m.material == kNoMaterial ? nullptr : &s.materials[m.material];
  if (!mat || mat->alpha_mode == AlphaMode::Opaque) c.repeated = drop_repeated_triangles(m, !mat || mat->double_sided);
  if (has_normals) {
    repair_normals(m);
  } else {
    compute_normals(m);
    m.flat = true;
  }
  s.meshes.push_back(std::move(m));
  c.mesh = int64_t(s.meshes.size() - 1);
  return c;
}

uint32_t vertex_colour_material(Scene& s) {
  for (size_t k = 0; k < s.materials.size(); ++k)
    if (s.materials[k].name == "vertex colours") return uint32_t(k);
  Material m;
  m.name = "vertex colours";
  m.double_sided = true;
  s.materials.push_back(m);
  return uint32_t(s.materials.size() - 1);
}

}  // namespace occ
