// Section planes: up to six half-spaces that cut a scene open (six make a section box). A point
// x is kept when n.x + d >= 0 for every plane (world coordinates, n a unit normal). They travel
// with the camera (Camera::sections): the renderer clips what they remove (gl_ClipDistance), and
// every culling test drops a box only when one plane removes all of it, with a margin for the
// renderer's float clip distances (cut_margin, math.hpp), so culled and brute-force frames stay
// equal.
#pragma once
#include <array>
#include <cstdint>
#include <string>

#include <glm/glm.hpp>

#include "common/math.hpp"

namespace occ {

struct Sections {
  static constexpr int kMax = 6;
  std::array<Plane, kMax> planes{};
  uint8_t count = 0;

  bool empty() const { return count == 0; }
  // Appends A,B,C,D (normalised). Throws InputError naming `what` for a seventh plane, a zero or
  // non-finite normal, or a non-finite D.
  void add(const glm::dvec4& abcd, const std::string& what);
  // "A,B,C,D" as four finite numbers; throws InputError naming `what` and the text.
  static glm::dvec4 parse(const std::string& text, const std::string& what);
  // Whether some plane removes all of `box` seen from `eye` (beyond the margin).
  bool removes(const Aabb& box, const glm::dvec3& eye) const;
  // Whether every plane keeps all of `box` (beyond the margin): nothing of it is clipped.
  bool keeps_all(const Aabb& box, const glm::dvec3& eye) const;
  // Whether every plane keeps point `p` beyond the margin (a triangle whose corners all are is
  // not clipped).
  bool keeps(const glm::dvec3& p, const glm::dvec3& eye) const;
  // "A,B,C,D;..." of the planes as given (normalised), for logs.
  std::string text() const;

  bool operator==(const Sections& o) const;
};

}  // namespace occ
