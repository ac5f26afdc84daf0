#include "common/math.hpp"

namespace occ {

Aabb Aabb::transformed(const glm::dmat4& m) const {
  Aabb out;
  if (empty()) return out;
  for (int i = 0; i < 8; ++i) {
    glm::dvec3 c{(i & 1) ? max.x : min.x, (i & 2) ? max.y : min.y, (i & 4) ? max.z : min.z};
    out.grow(glm::dvec3(m * glm::dvec4(c, 1.0)));
  }
  return out;
}

Containment Frustum::classify(const Aabb& box) const {
  if (box.empty()) return Containment::Outside;
  bool intersects = false;
  for (const Plane& pl : planes) {
    glm::dvec3 p{pl.n.x >= 0 ? box.max.x : box.min.x, pl.n.y >= 0 ? box.max.y : box.min.y,
                 pl.n.z >= 0 ? box.max.z : box.min.z};
    if (pl.distance(p) < 0) return Containment::Outside;
    glm::dvec3 n{pl.n.x >= 0 ? box.min.x : box.max.x, pl.n.y >= 0 ? box.min.y : box.max.y,
                 pl.n.z >= 0 ? box.min.z : box.max.z};
    if (pl.distance(n) < 0) intersects = true;
  }
  for (int i = 0; i < cut_count; ++i) {
    const Plane& pl = cuts[size_t(i)];
    glm::dvec3 p{pl.n.x >= 0 ? box.max.x : box.min.x, pl.n.y >= 0 ? box.max.y : box.min.y,
                 pl.n.z >= 0 ? box.max.z : box.min.z};
    if (pl.distance(p) < -cut_margin(pl, p, eye)) return Containment::Outside;
    glm::dvec3 n{pl.n.x >= 0 ? box.min.x : box.max.x, pl.n.y >= 0 ? box.min.y : box.max.y,
                 pl.n.z >= 0 ? box.min.z : box.max.z};
    if (pl.distance(n) <= cut_margin(pl, n, eye)) intersects = true;
  }
  return intersects ? Containment::Intersects : Containment::Inside;
}

}  // namespace occ
