// Quad grids, boxes and the parameter check of the generated scenes (scene_shapes.hpp).
#include "common/scene/scene_shapes.hpp"

#include "common/error.hpp"

namespace occ {

uint32_t add_mesh(Scene& s, Mesh m) {
  s.meshes.push_back(std::move(m));
  return uint32_t(s.meshes.size() - 1);
}

void add_grid(Mesh& m, glm::vec3 origin, glm::vec3 u, glm::vec3 v, int rows, int cols) {
  const glm::vec3 normal = glm::normalize(glm::cross(u, v));
  const auto base = uint32_t(m.positions.size());
  for (int r = 0; r <= rows; ++r)
    for (int c = 0; c <= cols; ++c) {
      m.positions.push_back(origin + u * (float(c) / float(cols)) + v * (float(r) / float(rows)));
      m.normals.push_back(normal);
    }
  auto at = [&](int r, int c) { return base + uint32_t(r * (cols + 1) + c); };
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < cols; ++c)
      m.indices.insert(m.indices.end(),
                       {at(r, c), at(r, c + 1), at(r + 1, c + 1), at(r, c), at(r + 1, c + 1), at(r + 1, c)});
}

Mesh box_mesh(const std::string& name, glm::vec3 lo, glm::vec3 hi, bool open_plus_x) {
  Mesh m;
  m.name = name;
  const glm::vec3 d = hi - lo;
  const glm::vec3 ex(d.x, 0, 0), ey(0, d.y, 0), ez(0, 0, d.z);
  add_grid(m, lo, ez, ey, 1, 1);                    // -x
  if (!open_plus_x) add_grid(m, lo + ex, ey, ez, 1, 1);  // +x
  add_grid(m, lo, ex, ez, 1, 1);                    // -y
  add_grid(m, lo + ey, ez, ex, 1, 1);               // +y
  add_grid(m, lo, ey, ex, 1, 1);                    // -z
  add_grid(m, lo + ez, ex, ey, 1, 1);               // +z
  return m;
}

void check_range(const std::string& where, const char* what, int v, int lo, int hi) {
  if (v < lo || v > hi)
    throw InputError(where + ": " + what + " must be " + std::to_string(lo) + ".." + std::to_string(hi) +
                     " (got " + std::to_string(v) + ")");
}

}  // namespace occ
