// The shared last steps of the model readers (model_mesh.hpp).
#include "common/scene/model_mesh.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <numeric>

namespace occ {

bool has_extension_ci(const std::string& path, std::string_view suffix) {
  if (path.size() < suffix.size()) return false;
  for (size_t i = 0; i < suffix.size(); ++i)
    if (std::tolower(static_cast<unsigned char>(path[path.size() - suffix.size() + i])) != suffix[i]) return false;
  return true;
}

namespace {

// Triangles [b, e) of `order` split at the median centroid along the longest axis until each part
// holds at most kMaxModelMeshTriangles; the parts' ranges appended to `out` in order.
void split_parts(const std::vector<glm::vec3>& centroid, std::vector<uint32_t>& order, size_t b, size_t e,
                 std::vector<std::pair<size_t, size_t>>& out) {
  if (e - b <= kMaxModelMeshTriangles) {
    std::sort(order.begin() + std::ptrdiff_t(b), order.begin() + std::ptrdiff_t(e));  // file order
    out.emplace_back(b, e);
    return;
  }
  glm::vec3 lo(INFINITY), hi(-INFINITY);
  for (size_t i = b; i < e; ++i) {
    lo = glm::min(lo, centroid[order[i]]);
    hi = glm::max(hi, centroid[order[i]]);
  }
  const glm::vec3 ext = hi - lo;
  const int axis = ext.x >= ext.y && ext.x >= ext.z ? 0 : ext.y >= ext.z ? 1 : 2;
  const size_t mid = b + (e - b) / 2;
  std::nth_element(order.begin() + std::ptrdiff_t(b), order.begin() + std::ptrdiff_t(mid),
                   order.begin() + std::ptrdiff_t(e), [&](uint32_t x, uint32_t y) {
                     const float cx = centroid[x][axis], cy = centroid[y][axis];
                     return cx < cy || (cx == cy && x < y);  // a total order: deterministic
                   });
  split_parts(centroid, order, b, mid, out);
  split_parts(centroid, order, mid, e, out);
}

// Mesh m's triangles order[b, e) as a mesh of their own with the vertices they use (in first-use
// order), its name and material kept.
Mesh part_of(const Mesh& m, const std::vector<uint32_t>& order, size_t b, size_t e, std::vector<uint32_t>& local) {
  Mesh p;
  p.name = m.name;
  p.material = m.material;
  p.flat = m.flat;
  constexpr uint32_t kNone = 0xffffffffu;
  std::vector<uint32_t> used;
  p.indices.reserve(3 * (e - b));
  for (size_t i = b; i < e; ++i)
    for (int k = 0; k < 3; ++k) {
      const uint32_t v = m.indices[3 * size_t(order[i]) + size_t(k)];
      if (local[v] == kNone) {
        local[v] = uint32_t(used.size());
        used.push_back(v);
      }
      p.indices.push_back(local[v]);
    }
  for (uint32_t v : used) {
    p.positions.push_back(m.positions[v]);
    p.normals.push_back(m.normals[v]);
    if (!m.uvs.empty()) p.uvs.push_back(m.uvs[v]);
    if (!m.colors.empty()) p.colors.push_back(m.colors[v]);
    local[v] = kNone;
  }
  return p;
}

}  // namespace

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
  const size_t tris = m.indices.size() / 3;
  if (tris <= kMaxModelMeshTriangles) {
    s.meshes.push_back(std::move(m));
    c.meshes.push_back(uint32_t(s.meshes.size() - 1));
    return c;
  }
  std::vector<glm::vec3> centroid(tris);
  for (size_t t = 0; t < tris; ++t)
    centroid[t] = (m.positions[m.indices[3 * t]] + m.positions[m.indices[3 * t + 1]] + m.positions[m.indices[3 * t + 2]]) / 3.0f;
  std::vector<uint32_t> order(tris);
  std::iota(order.begin(), order.end(), 0u);
  std::vector<std::pair<size_t, size_t>> parts;
  split_parts(centroid, order, 0, tris, parts);
  centroid = {};
  std::vector<uint32_t> local(m.positions.size(), 0xffffffffu);
  for (auto [b, e] : parts) {
    s.meshes.push_back(part_of(m, order, b, e, local));
    c.meshes.push_back(uint32_t(s.meshes.size() - 1));
  }
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
