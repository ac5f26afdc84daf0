// Bounding boxes, planes and frustum tests in double precision (world coordinates may be
// large: scenes far from the origin). Pure math, no GL.
#pragma once
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>

#include <glm/glm.hpp>

namespace occ {

struct Aabb {
  glm::dvec3 min{std::numeric_limits<double>::infinity()};
  glm::dvec3 max{-std::numeric_limits<double>::infinity()};

  bool empty() const { return !(min.x <= max.x && min.y <= max.y && min.z <= max.z); }
  void grow(const glm::dvec3& p) {
    min = glm::min(min, p);
    max = glm::max(max, p);
  }
  void grow(const Aabb& b) {
    if (b.empty()) return;
    min = glm::min(min, b.min);
    max = glm::max(max, b.max);
  }
  glm::dvec3 center() const { return 0.5 * (min + max); }
  glm::dvec3 extent() const { return max - min; }
  double diagonal() const { return empty() ? 0.0 : glm::length(max - min); }
  // Closed box: points on a face count as inside.
  bool contains(const glm::dvec3& p) const {
    return p.x >= min.x && p.x <= max.x && p.y >= min.y && p.y <= max.y && p.z >= min.z &&
           p.z <= max.z;
  }
  // Squared distance from p to the box (0 when inside or on it).
  double distance2(const glm::dvec3& p) const {
    glm::dvec3 d = glm::max(glm::max(min - p, p - max), glm::dvec3(0.0));
    return glm::dot(d, d);
  }
  // Box of the 8 transformed corners.
  Aabb transformed(const glm::dmat4& m) const;
  bool operator==(const Aabb&) const = default;
};

// Plane n.x + d = 0; points with n.x + d >= 0 are on the inner side.
struct Plane {
  glm::dvec3 n{0, 0, 1};
  double d = 0;
  double distance(const glm::dvec3& p) const { return glm::dot(n, p) + d; }
};

enum class Containment { Outside, Intersects, Inside };

// How far below 0 a section plane's distance to `p` must be, seen from `eye`, before the plane
// surely removes p: the error bound of the float clip distance the renderer computes for it,
// relative to the distances involved (common/section.hpp).
inline double cut_margin(const Plane& pl, const glm::dvec3& p, const glm::dvec3& eye) {
  constexpr double kRelative = 1e-5;
  const glm::dvec3 v = p - eye;
  return kRelative * (1.0 + std::abs(pl.distance(eye)) + std::sqrt(glm::dot(v, v)));
}

// Six inward-facing planes: left, right, bottom, top, near, far.
struct Frustum {
  std::array<Plane, 6> planes;
  // Section planes (Camera::sections): a box one of them removes beyond cut_margin is Outside,
  // one any of them cuts is at most Intersects.
  std::array<Plane, 6> cuts{};
  uint8_t cut_count = 0;
  glm::dvec3 eye{0.0};

  // p/n-vertex test (culling lecture): for each plane, the p-vertex is the box corner farthest
  // along the normal. If it is behind the plane, the whole box is outside. If the n-vertex
  // (nearest corner) is behind some plane, the box intersects. Conservative: a box may be
  // reported Intersects while being outside (corner cases near frustum edges), never the reverse.
  Containment classify(const Aabb& box) const;
  bool culls(const Aabb& box) const { return classify(box) == Containment::Outside; }
};

}  // namespace occ
