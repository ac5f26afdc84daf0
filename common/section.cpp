#include "common/section.hpp"

#include <cmath>
#include <cstdio>
#include <optional>
#include <vector>

#include "common/cli.hpp"
#include "common/error.hpp"

namespace occ {

void Sections::add(const glm::dvec4& abcd, const std::string& what) {
  if (count >= kMax) throw InputError(what + ": at most " + std::to_string(kMax) + " section planes");
  const glm::dvec3 n(abcd);
  const double len = glm::length(n);
  if (!std::isfinite(len) || !(len > 0) || !std::isfinite(abcd.w))
    throw InputError(what + ": a section plane needs a non-zero finite normal (A,B,C) and a finite D");
  planes[count++] = Plane{n / len, abcd.w / len};
}

glm::dvec4 Sections::parse(const std::string& text, const std::string& what) {
  std::vector<std::string> parts(1);
  for (char c : text) {
    if (c == ',')
      parts.emplace_back();
    else
      parts.back() += c;
  }
  glm::dvec4 v(0.0);
  bool ok = parts.size() == 4;
  for (size_t i = 0; ok && i < 4; ++i) {
    const std::optional<double> x = parse_finite(parts[i]);
    ok = x.has_value();
    if (ok) v[int(i)] = *x;
  }
  if (!ok)
    throw InputError(what + " '" + text + "': expected A,B,C,D (four finite numbers: keeps A*x + B*y + C*z + D >= 0)");
  return v;
}

bool Sections::removes(const Aabb& box, const glm::dvec3& eye) const {
  for (int i = 0; i < count; ++i) {
    const Plane& pl = planes[size_t(i)];
    const glm::dvec3 p{pl.n.x >= 0 ? box.max.x : box.min.x, pl.n.y >= 0 ? box.max.y : box.min.y,
                       pl.n.z >= 0 ? box.max.z : box.min.z};
    if (pl.distance(p) < -cut_margin(pl, p, eye)) return true;
  }
  return false;
}

bool Sections::keeps_all(const Aabb& box, const glm::dvec3& eye) const {
  for (int i = 0; i < count; ++i) {
    const Plane& pl = planes[size_t(i)];
    const glm::dvec3 q{pl.n.x >= 0 ? box.min.x : box.max.x, pl.n.y >= 0 ? box.min.y : box.max.y,
                       pl.n.z >= 0 ? box.min.z : box.max.z};
    if (pl.distance(q) <= cut_margin(pl, q, eye)) return false;
  }
  return true;
}

bool Sections::keeps(const glm::dvec3& p, const glm::dvec3& eye) const {
  for (int i = 0; i < count; ++i)
    if (planes[size_t(i)].distance(p) <= cut_margin(planes[size_t(i)], p, eye)) return false;
  return true;
}

std::string Sections::text() const {
  std::string s;
  for (int i = 0; i < count; ++i) {
    const Plane& p = planes[size_t(i)];
    char b[128];
    std::snprintf(b, sizeof b, "%s%.9g,%.9g,%.9g,%.9g", i ? ";" : "", p.n.x, p.n.y, p.n.z, p.d);
    s += b;
  }
  return s;
}

bool Sections::operator==(const Sections& o) const {
  if (count != o.count) return false;
  for (int i = 0; i < count; ++i)
    if (planes[size_t(i)].n != o.planes[size_t(i)].n || planes[size_t(i)].d != o.planes[size_t(i)].d) return false;
  return true;
}

}  // namespace occ
