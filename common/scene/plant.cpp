// The procedural plant (layout in plant.hpp). One pass, single-threaded, deterministic: bays are
// filled column by column along x (columns of nz bays, each bay level by level) until the
// triangle budget is spent, then the hall is closed by ground, outer walls and roof around the
// bays used. Every object is built in its own mesh, in coordinates relative to the object's
// origin (float mesh, double transform), and the mesh vectors are trimmed to size.
#include "common/scene/plant.hpp"

#include <algorithm>
#include <cmath>
#include <glm/gtc/matrix_transform.hpp>
#include <string>

#include "common/error.hpp"
#include "common/hash.hpp"

namespace occ::plant {
namespace {

using glm::dvec3;

constexpr double kPi = 3.14159265358979323846;
constexpr double kSlab = 0.3;   // floor slab thickness (upper levels, roof)
constexpr double kWall = 0.3;   // outer wall thickness

// splitmix64: the same sequence on every platform.
class Rng {
 public:
  explicit Rng(uint64_t seed) : s_(seed) {}
  uint64_t next() { return mix64(s_ += 0x9e3779b97f4a7c15ULL); }
  double uniform(double lo, double hi) { return lo + (hi - lo) * double(next() >> 11) * 0x1.0p-53; }
  int pick(int lo, int hi) { return lo + int(next() % uint64_t(hi - lo + 1)); }  // [lo, hi]
  bool chance(double p) { return uniform(0, 1) < p; }

 private:
  uint64_t s_;
};

// Two unit vectors u, v with cross(u, v) = a (a unit).
void basis(const dvec3& a, dvec3& u, dvec3& v) {
  const dvec3 helper = std::abs(a.y) < 0.9 ? dvec3(0, 1, 0) : dvec3(1, 0, 0);
  u = glm::normalize(glm::cross(helper, a));
  v = glm::cross(a, u);
}

// One object's mesh, built in world coordinates and stored relative to `origin`.
class Builder {
 public:
  explicit Builder(const dvec3& origin) : origin_(origin) {}

  uint32_t vert(const dvec3& p, const dvec3& n) {
    m_.positions.emplace_back(p - origin_);
    m_.normals.emplace_back(n);
    return uint32_t(m_.positions.size() - 1);
  }
  void tri(uint32_t a, uint32_t b, uint32_t c) { m_.indices.insert(m_.indices.end(), {a, b, c}); }

  // A quad o, o+u, o+u+v, o+v facing cross(u, v), split into rows x cols.
  void face(const dvec3& o, const dvec3& u, const dvec3& v, int rows = 1, int cols = 1) {
    const dvec3 n = glm::normalize(glm::cross(u, v));
    const auto base = uint32_t(m_.positions.size());
    for (int r = 0; r <= rows; ++r)
      for (int c = 0; c <= cols; ++c) vert(o + u * (double(c) / cols) + v * (double(r) / rows), n);
    auto at = [&](int r, int c) { return base + uint32_t(r * (cols + 1) + c); };
    for (int r = 0; r < rows; ++r)
      for (int c = 0; c < cols; ++c) {
        tri(at(r, c), at(r, c + 1), at(r + 1, c + 1));
        tri(at(r, c), at(r + 1, c + 1), at(r + 1, c));
      }
  }

  // Axis-aligned box [lo, hi], outward faces; `panel` > 0 subdivides the sides into panels of
  // about that size (boiler casings).
  void box(const dvec3& lo, const dvec3& hi, double panel = 0.0) {
    const dvec3 d = hi - lo, ex(d.x, 0, 0), ey(0, d.y, 0), ez(0, 0, d.z);
    auto n = [&](double len) { return panel > 0 ? std::max(1, int(len / panel)) : 1; };
    face(lo, ez, ey, n(d.y), n(d.z));        // -x
    face(lo + ex, ey, ez, n(d.z), n(d.y));   // +x
    face(lo, ex, ez, 1, 1);                  // -y
    face(lo + ey, ez, ex, 1, 1);             // +y
    face(lo, ey, ex, n(d.x), n(d.y));        // -z
    face(lo + ez, ex, ey, n(d.y), n(d.x));   // +z
  }

  // Ring of `seg` vertices at centre c with basis (u, v), radius r (normals radial).
  uint32_t ring(const dvec3& c, const dvec3& u, const dvec3& v, double r, int seg) {
    const auto base = uint32_t(m_.positions.size());
    for (int i = 0; i < seg; ++i) {
      const double phi = 2.0 * kPi * i / seg;
      const dvec3 n = u * std::cos(phi) + v * std::sin(phi);
      vert(c + r * n, n);
    }
    return base;
  }
  // Side quads between consecutive rings a -> b (b further along cross(u, v)).
  void connect(uint32_t a, uint32_t b, int seg) {
    for (int i = 0; i < seg; ++i) {
      const uint32_t i1 = uint32_t((i + 1) % seg);
      tri(a + uint32_t(i), a + i1, b + i1);
      tri(a + uint32_t(i), b + i1, b + uint32_t(i));
    }
  }
  // A flat disc at c facing n.
  void cap(const dvec3& c, const dvec3& n, double r, int seg) {
    dvec3 u, v;
    basis(n, u, v);
    const uint32_t centre = vert(c, n);
    const auto base = uint32_t(m_.positions.size());
    for (int i = 0; i < seg; ++i) {
      const double phi = 2.0 * kPi * i / seg;
      vert(c + r * (u * std::cos(phi) + v * std::sin(phi)), n);
    }
    for (int i = 0; i < seg; ++i) tri(centre, base + uint32_t(i), base + uint32_t((i + 1) % seg));
  }

  // A cylinder p0 -> p1 with `rings` sections along its length and optional end caps.
  void cylinder(const dvec3& p0, const dvec3& p1, double r, int seg, int rings = 1, bool cap0 = false,
                bool cap1 = false) {
    const dvec3 a = glm::normalize(p1 - p0);
    dvec3 u, v;
    basis(a, u, v);
    uint32_t prev = ring(p0, u, v, r, seg);
    for (int j = 1; j <= rings; ++j) {
      const uint32_t next = ring(p0 + (p1 - p0) * (double(j) / rings), u, v, r, seg);
      connect(prev, next, seg);
      prev = next;
    }
    if (cap0) cap(p0, -a, r, seg);
    if (cap1) cap(p1, a, r, seg);
  }

  // A 90-degree pipe bend: arrives at `corner` along d0, leaves along d1 (unit, perpendicular),
  // bend radius R, pipe radius r, `steps` sections.
  void elbow(const dvec3& corner, const dvec3& d0, const dvec3& d1, double r, double R, int seg, int steps) {
    const dvec3 centre = corner - d0 * R + d1 * R, b = glm::cross(d0, d1);
    uint32_t prev = 0;
    for (int s = 0; s <= steps; ++s) {
      const double t = 0.5 * kPi * s / steps;
      const dvec3 w = -d1 * std::cos(t) + d0 * std::sin(t);  // from the bend centre outwards
      const uint32_t cur = ring(centre + R * w, b, w, r, seg);  // cross(b, w) = direction of travel
      if (s > 0) connect(prev, cur, seg);
      prev = cur;
    }
  }

  // A 2:1 ellipsoidal vessel head on the circle (c, radius r) bulging along unit `axis`.
  void head(const dvec3& c, const dvec3& axis, double r, int seg, int lat) {
    dvec3 u, v;
    basis(axis, u, v);
    const double h = 0.5 * r;
    uint32_t prev = 0;
    for (int k = 0; k < lat; ++k) {
      const double th = 0.5 * kPi * k / lat;
      const auto base = uint32_t(m_.positions.size());
      for (int i = 0; i < seg; ++i) {
        const double phi = 2.0 * kPi * i / seg;
        const dvec3 radial = u * std::cos(phi) + v * std::sin(phi);
        vert(c + radial * (r * std::cos(th)) + axis * (h * std::sin(th)),
             glm::normalize(radial * (std::cos(th) / r) + axis * (std::sin(th) / h)));
      }
      if (k > 0) connect(prev, base, seg);
      prev = base;
    }
    const uint32_t pole = vert(c + axis * h, axis);
    for (int i = 0; i < seg; ++i) tri(prev + uint32_t(i), prev + uint32_t((i + 1) % seg), pole);
  }

  // An I-beam from p0 to p1 along axis `along`, web along axis `web` (height h), flanges w wide.
  void ibeam(const dvec3& p0, double length, int along, int web, double h, double w) {
    const int side = 3 - along - web;
    const double tf = 0.08 * h, tw = 0.06 * h;
    auto part = [&](double web_lo, double web_hi, double half_width) {
      dvec3 lo = p0, hi = p0;
      hi[along] += length;
      lo[web] += web_lo;
      hi[web] += web_hi;
      lo[side] -= half_width;
      hi[side] += half_width;
      box(lo, hi);
    };
    part(-0.5 * h, -0.5 * h + tf, 0.5 * w);
    part(-0.5 * h + tf, 0.5 * h - tf, 0.5 * tw);
    part(0.5 * h - tf, 0.5 * h, 0.5 * w);
  }

  Mesh take(std::string name) {
    m_.positions.shrink_to_fit();
    m_.normals.shrink_to_fit();
    m_.indices.shrink_to_fit();
    m_.name = std::move(name);
    return std::move(m_);
  }
  uint64_t triangles() const { return m_.indices.size() / 3; }

 private:
  dvec3 origin_;
  Mesh m_;
};

class Generator {
 public:
  explicit Generator(const PlantParams& p) : rng_(p.seed), target_(uint64_t(p.millions * 1e6)) {
    // Finer tessellation in bigger plants, so objects stay in the tens of thousands (not ~1M).
    q_ = std::pow(std::max(1.0, p.millions / 13.0), 0.25);
    const double per_bay = kLevels * 6500.0 * q_ * q_;  // measured average, all levels of a bay
    const double bays = double(target_) / per_bay;
    nz_ = std::max(2, 2 * int(std::lround(0.5 * std::sqrt(bays / 2.5))));
    half_width_ = 0.5 * kAisle + 0.5 * nz_ * kBay;
  }

  Scene run() {
    int columns = 0;
    for (int i = 0; !done(); ++i) {
      for (int k = 0; k < nz_ && !done(); ++k)
        for (int level = 0; level < kLevels && !done(); ++level) bay(i, k, level);
      columns = i + 1;
    }
    close_hall(columns);
    scene_.source = "plant";
    // Closed solids with outward faces, as a CAD export has them: one single-sided material
    // (back faces culled, glTF doubleSided false) with the per-object colour of generated scenes.
    Material solid;
    solid.name = "plant solid";
    solid.object_color = true;
    solid.double_sided = false;
    scene_.materials.push_back(solid);
    for (Mesh& m : scene_.meshes) m.material = 0;
    return std::move(scene_);
  }

 private:
  bool done() const { return triangles_ >= target_; }
  int seg(double n) const { return std::max(3, int(std::lround(n * q_))); }

  void add(Builder& b, const dvec3& origin, const char* kind) {
    if (b.triangles() == 0) return;
    triangles_ += b.triangles();
    std::string name = std::string(kind) + " " + std::to_string(scene_.objects.size());
    scene_.meshes.push_back(b.take(name));
    scene_.objects.push_back(
        Object{uint32_t(scene_.meshes.size() - 1), glm::translate(glm::dmat4(1.0), origin), std::move(name)});
  }

  // Bay k (0..nz-1) spans z from -half_width (k = 0) to -aisle/2 (k = nz/2 - 1), then from
  // +aisle/2 to +half_width.
  double bay_z0(int k) const {
    const int h = nz_ / 2;
    return k < h ? -half_width_ + k * kBay : 0.5 * kAisle + (k - h) * kBay;
  }

  static constexpr double kBeamH = 0.45, kBeamW = 0.3;  // the beams under each slab

  // Where one bay stands: x0..x1, z0..z1 on its level's floor y0, up to `top` (under the next
  // slab); near_aisle for the bays beside the central aisle, aisle_edge the bay's edge towards z = 0.
  struct BaySpace {
    int k, level;
    double x0, x1, z0, z1, y0, top;
    bool near_aisle;
    double aisle_edge;
  };
  // The floor of a bay that main equipment may use (a 1 m margin inside the bay) and the height
  // free above it.
  struct EquipmentSpace {
    double ex0, ex1, ez0, ez1, y0, room;
  };

  // Bay k of column i on `level`: its slab, frame, equipment, cable tray and pipe runs, in that
  // order, each while the triangle budget lasts.
  void bay(int i, int k, int level) {
    const double x0 = i * kBay, z0 = bay_z0(k), y0 = level * kLevelHeight;
    const double x1 = x0 + kBay, z1 = z0 + kBay, top = y0 + kLevelHeight - kSlab;  // under the next slab
    const bool near_aisle = k == nz_ / 2 - 1 || k == nz_ / 2;
    const double aisle_edge = k < nz_ / 2 ? z1 : z0;  // the bay's edge towards z = 0
    const BaySpace b{k, level, x0, x1, z0, z1, y0, top, near_aisle, aisle_edge};

    if (level > 0 && rng_.chance(0.8)) floor_slab(b);  // some bays are open to the level below
    frame(b);
    if (done()) return;
    equipment(b);
    if (!done() && rng_.chance(0.4)) cable_tray(b);
    const int runs = rng_.pick(3, 9);
    for (int n = 0; n < runs && !done(); ++n) pipe_run(x0, x1, z0, z1, y0, top - kBeamH, near_aisle, level, k);
  }

  // The floor slab, and a railing along the aisle for the bays beside it.
  void floor_slab(const BaySpace& bs) {
    const auto& [k, level, x0, x1, z0, z1, y0, top, near_aisle, aisle_edge] = bs;
    const dvec3 corner(x0, y0, z0);
    Builder b(corner);
    b.box({x0, y0 - kSlab, z0}, {x1, y0, z1});
    add(b, corner, "slab");
    if (near_aisle) {  // railing along the aisle
      Builder r(corner);
      const double z = aisle_edge + (k < nz_ / 2 ? -0.1 : 0.1);
      for (double x = x0 + 0.5; x < x1; x += 2.0) r.cylinder({x, y0, z}, {x, y0 + 1.1, z}, 0.025, 6);
      r.cylinder({x0, y0 + 1.1, z}, {x1, y0 + 1.1, z}, 0.03, 8);
      r.cylinder({x0, y0 + 0.55, z}, {x1, y0 + 0.55, z}, 0.025, 6);
      add(r, corner, "railing");
    }
  }

  // Columns at the bay's -x corners (and the far corner of the outermost bays), and the beams
  // under the next slab: along x at both z edges' nearest side, along z at x0 and mid-x.
  void frame(const BaySpace& bs) {
    const auto& [k, level, x0, x1, z0, z1, y0, top, near_aisle, aisle_edge] = bs;
    for (double z : {z0, z1}) {
      if (z == z1 && k != nz_ / 2 - 1 && k != nz_ - 1) continue;  // owned by the next bay
      Builder b({x0, y0, z});
      b.ibeam({x0, y0, z}, top - y0, 1, 0, 0.4, 0.35);
      add(b, {x0, y0, z}, "column");
    }
    const double yb = top - 0.5 * kBeamH;
    for (double z : {z0 + 0.2, z1 - 0.2}) {
      Builder b({x0, yb, z});
      b.ibeam({x0, yb, z}, kBay, 0, 1, kBeamH, kBeamW);
      add(b, {x0, yb, z}, "beam");
    }
    for (double x : {x0 + 0.2, x0 + 0.5 * kBay}) {
      Builder b({x, yb, z0});
      b.ibeam({x, yb, z0}, kBay, 2, 1, x == x0 + 0.2 ? kBeamH : 0.7 * kBeamH, kBeamW);
      add(b, {x, yb, z0}, "beam");
    }
  }

  // Main equipment on the floor, inside a 1 m margin: a tank, a boiler, a heat exchanger, pumps,
  // a horizontal vessel, or nothing (an open bay).
  void equipment(const BaySpace& bs) {
    const EquipmentSpace e{bs.x0 + 1, bs.x1 - 1, bs.z0 + 1, bs.z1 - 1, bs.y0, bs.top - kBeamH - bs.y0 - 0.3};
    const double kind = rng_.uniform(0, 1);
    if (kind < 0.25) tank(e);
    else if (kind < 0.40) boiler(e);
    else if (kind < 0.55) exchanger(e);
    else if (kind < 0.75) pumps(e);
    else if (kind < 0.90) vessel(e);
  }

  // A vertical tank with a vessel head.
  void tank(const EquipmentSpace& es) {
    const auto& [ex0, ex1, ez0, ez1, y0, room] = es;
    const double r = rng_.uniform(1.5, 4.0), cx = 0.5 * (ex0 + ex1) + rng_.uniform(-4.0 + r, 4.0 - r),
                 cz = 0.5 * (ez0 + ez1) + rng_.uniform(-4.0 + r, 4.0 - r);
    const double h = std::max(1.5, rng_.uniform(0.5, 1.0) * (room - 0.5 * r));
    const dvec3 base(cx, y0, cz);
    Builder b(base);
    const int s = seg(rng_.pick(3, 6) * 8.0);
    b.cylinder(base, base + dvec3(0, h, 0), r, s, rng_.pick(2, 8), true, false);
    b.head(base + dvec3(0, h, 0), {0, 1, 0}, r, s, seg(rng_.pick(3, 8)));
    add(b, base, "tank");
  }

  // A boiler: panelled casing and an exposed tube bank beside it.
  void boiler(const EquipmentSpace& es) {
    const auto& [ex0, ex1, ez0, ez1, y0, room] = es;
    const double w = rng_.uniform(5.0, 8.0), d = rng_.uniform(3.0, 5.0), h = room - 0.2;
    const dvec3 lo(ex0, y0, ez0);
    Builder b(lo);
    b.box(lo, lo + dvec3(w, h, d), rng_.uniform(0.5, 1.5));
    add(b, lo, "boiler");
    Builder t(lo);
    const int nx = rng_.pick(4, 12), nzt = rng_.pick(3, 10);
    const double tr = rng_.uniform(0.03, 0.08);
    for (int a = 0; a < nx; ++a)
      for (int c = 0; c < nzt; ++c) {
        const dvec3 p(ex0 + 0.3 + a * (w - 0.6) / std::max(1, nx - 1), y0 + 0.3, ez0 + d + 0.3 + c * 0.25);
        if (p.z + tr > ez1) continue;
        t.cylinder(p, p + dvec3(0, h - 0.6, 0), tr, seg(8), rng_.pick(1, 4));
      }
    add(t, lo, "tubes");
  }

  // A heat exchanger: shell with heads on saddles, tube bundle inside.
  void exchanger(const EquipmentSpace& es) {
    const auto& [ex0, ex1, ez0, ez1, y0, room] = es;
    const double r = rng_.uniform(0.5, 1.1), len = rng_.uniform(5.0, 9.0);
    const double cy = y0 + std::min(room - r - 0.1, rng_.uniform(1.0, 2.5) + r * 0.5);
    const dvec3 p0(ex0 + 0.5, std::max(cy, y0 + r + 0.2), 0.5 * (ez0 + ez1) + rng_.uniform(-2.0, 2.0));
    const dvec3 p1 = p0 + dvec3(len, 0, 0);
    Builder b(p0);
    const int s = seg(rng_.pick(2, 5) * 8.0);
    b.cylinder(p0, p1, r, s, rng_.pick(1, 6));
    b.head(p1, {1, 0, 0}, r, s, seg(4));
    b.head(p0, {-1, 0, 0}, r, s, seg(4));
    for (double x : {p0.x + 0.2 * len, p0.x + 0.8 * len})
      b.box({x - 0.15, y0, p0.z - 0.7 * r}, {x + 0.15, p0.y - 0.8 * r, p0.z + 0.7 * r});
    add(b, p0, "exchanger");
    Builder t(p0);  // hidden inside the shell: depth complexity no eye ever sees
    const int tubes = rng_.pick(20, 120);
    for (int n = 0; n < tubes; ++n) {
      const double a = 2.0 * kPi * n * 0.618033988749895, rr = 0.8 * r * std::sqrt((n + 0.5) / tubes);
      const dvec3 o(0, rr * std::cos(a), rr * std::sin(a));
      t.cylinder(p0 + o, p1 + o, 0.015, seg(6), rng_.pick(1, 3));
    }
    add(t, p0, "bundle");
  }

  // 2..5 pumps, each a base plate, a motor and a casing with its nozzle.
  void pumps(const EquipmentSpace& es) {
    const auto& [ex0, ex1, ez0, ez1, y0, room] = es;
    const int count = rng_.pick(2, 5);
    for (int n = 0; n < count && !done(); ++n) {
      const dvec3 base(rng_.uniform(ex0, ex1 - 2.0), y0, rng_.uniform(ez0, ez1 - 1.0));
      Builder b(base);
      b.box(base, base + dvec3(2.0, 0.3, 0.8));
      const double mr = rng_.uniform(0.2, 0.35);
      b.cylinder(base + dvec3(0.1, 0.3 + mr, 0.4), base + dvec3(1.1, 0.3 + mr, 0.4), mr, seg(16), 2, true, true);
      b.cylinder(base + dvec3(1.5, 0.3, 0.4), base + dvec3(1.5, 0.9, 0.4), 0.3, seg(16), 1, false, true);
      b.cylinder(base + dvec3(1.5, 0.9, 0.4), base + dvec3(1.5, 1.5, 0.4), 0.1, seg(12), 1, false, true);
      add(b, base, "pump");
    }
  }

  // A horizontal vessel along z on saddles.
  void vessel(const EquipmentSpace& es) {
    const auto& [ex0, ex1, ez0, ez1, y0, room] = es;
    const double r = rng_.uniform(0.8, std::min(2.0, 0.5 * room)), len = rng_.uniform(4.0, 8.0);
    const dvec3 p0(0.5 * (ex0 + ex1) + rng_.uniform(-2.0, 2.0), y0 + r + 0.4, ez0 + 0.5 * (10.0 - len));
    const dvec3 p1 = p0 + dvec3(0, 0, len);
    Builder b(p0);
    const int s = seg(rng_.pick(3, 6) * 8.0);
    b.cylinder(p0, p1, r, s, rng_.pick(1, 4));
    b.head(p1, {0, 0, 1}, r, s, seg(5));
    b.head(p0, {0, 0, -1}, r, s, seg(5));
    for (double z : {p0.z + 0.2 * len, p0.z + 0.8 * len})
      b.box({p0.x - 0.7 * r, y0, z - 0.15}, {p0.x + 0.7 * r, p0.y - 0.8 * r, z + 0.15});
    add(b, p0, "vessel");
  }

  // A cable tray along x under the beams.
  void cable_tray(const BaySpace& bs) {
    const auto& [k, level, x0, x1, z0, z1, y0, top, near_aisle, aisle_edge] = bs;
    const double y = top - kBeamH - 0.3, z = rng_.uniform(z0 + 0.5, z1 - 0.5);
    Builder b({x0, y, z});
    b.box({x0, y - 0.1, z - 0.3}, {x1, y, z + 0.3});
    add(b, {x0, y, z}, "tray");
  }

  // A run of straight pipes joined by elbows, with flanges at both ends. Stays inside the bay's
  // side of the hall (x within half a bay of the bay); some runs near the aisle cross it overhead.
  void pipe_run(double x0, double x1, double z0, double z1, double y0, double ceiling, bool near_aisle, int level,
                int k) {
    static constexpr double kRadii[] = {0.03, 0.05, 0.05, 0.08, 0.08, 0.1, 0.1, 0.15, 0.2, 0.25, 0.3, 0.4};
    const double r = kRadii[rng_.pick(0, 11)], R = std::max(1.5 * r, 0.08), margin = r + 0.05;
    const int s = seg(r < 0.07 ? 8.0 : r < 0.15 ? 12.0 : r < 0.25 ? 16.0 : 24.0);
    const int steps = seg(r < 0.1 ? 4.0 : 6.0);
    // The region the run may use.
    const bool neg = k < nz_ / 2;
    dvec3 lo(std::max(0.2, x0 - 0.5 * kBay) + margin, y0 + 0.2 + margin, neg ? -half_width_ : 0.5 * kAisle);
    dvec3 hi(x1 + 0.5 * kBay - margin, ceiling - 0.1 - margin, neg ? -0.5 * kAisle : half_width_);
    lo.z += margin;
    hi.z -= margin;
    std::vector<dvec3> pts;
    dvec3 p(rng_.uniform(x0 + margin, x1 - margin), rng_.uniform(lo.y, hi.y), rng_.uniform(z0 + margin, z1 - margin));
    pts.push_back(p);
    const double cross_y = level == 0 ? kAisleClear + 0.5 : y0 + 2.5;
    if (near_aisle && hi.y > cross_y + 0.5 && rng_.chance(0.3)) {  // up, across the aisle, down
      const double y = rng_.uniform(cross_y + margin, hi.y);
      const double z_far = (neg ? 1 : -1) * rng_.uniform(0.5 * kAisle + 1.0, 0.5 * kAisle + kBay - 1.0);
      if (std::abs(y - p.y) > 2 * R + 0.2) {
        pts.push_back({p.x, y, p.z});
        pts.push_back({p.x, y, z_far});
        pts.push_back({p.x, std::max(y0 + 0.5, y - rng_.uniform(1.0, 3.0)), z_far});
      } else {
        pts.back().y = y;
        pts.push_back({p.x, y, z_far});
      }
    } else {
      const int segments = rng_.pick(2, 6);
      int prev_axis = -1;
      for (int n = 0; n < segments; ++n) {
        int axis = rng_.pick(0, 2);
        if (axis == prev_axis) axis = (axis + 1 + rng_.pick(0, 1)) % 3;
        const double len = axis == 1 ? rng_.uniform(1.0, 3.0) : rng_.uniform(1.5, 9.0);
        dvec3 q = pts.back();
        q[axis] += rng_.chance(0.5) ? len : -len;
        q[axis] = std::clamp(q[axis], lo[axis], hi[axis]);
        const double need = (n == 0 ? R : 2 * R) + 0.1;
        if (std::abs(q[axis] - pts.back()[axis]) < need) break;
        pts.push_back(q);
        prev_axis = axis;
      }
    }
    if (pts.size() < 2) return;
    Builder b(pts.front());
    for (size_t n = 0; n + 1 < pts.size(); ++n) {
      const dvec3 d = glm::normalize(pts[n + 1] - pts[n]);
      const dvec3 a = pts[n] + (n > 0 ? d * R : dvec3(0.0));
      const dvec3 e = pts[n + 1] - (n + 2 < pts.size() ? d * R : dvec3(0.0));
      b.cylinder(a, e, r, s);
      if (n + 2 < pts.size()) b.elbow(pts[n + 1], d, glm::normalize(pts[n + 2] - pts[n + 1]), r, R, s, steps);
    }
    const dvec3 d0 = glm::normalize(pts[1] - pts[0]), d1 = glm::normalize(pts.back() - pts[pts.size() - 2]);
    b.cylinder(pts.front(), pts.front() + d0 * 0.06, 1.6 * r, s, 1, true, true);  // flanges
    b.cylinder(pts.back() - d1 * 0.06, pts.back(), 1.6 * r, s, 1, true, true);
    add(b, pts.front(), "pipe");
  }

  // Ground under every bay and the aisle, outer walls (one panel per bay and level) and a roof.
  // The hall is longer in x than wide in z (the walk follows the longer axis).
  void close_hall(int columns) {
    const double x_end = std::max(columns * kBay + 0.5 * kBay, 2.0 * half_width_ + kBay);
    const int nx = int(std::ceil(x_end / kBay));
    const double length = nx * kBay, height = kLevels * kLevelHeight;
    for (int i = 0; i < nx; ++i) {
      const double x0 = i * kBay, x1 = x0 + kBay;
      const dvec3 o(x0, 0, -half_width_);
      Builder g(o);
      g.face(o, {0, 0, 2 * half_width_}, {kBay, 0, 0});  // ground, facing +y
      add(g, o, "ground");
      Builder roof(o);
      roof.box({x0, height, -half_width_}, {x1, height + kSlab, half_width_});
      add(roof, o, "roof");
      for (int side : {-1, 1}) {
        const double z = side * (half_width_ + 0.5 * kWall);
        for (int level = 0; level < kLevels; ++level) {
          const dvec3 lo(x0, level * kLevelHeight, z - 0.5 * kWall);
          Builder w(lo);
          w.box(lo, {x1, lo.y + kLevelHeight, z + 0.5 * kWall});
          add(w, lo, "wall");
        }
      }
    }
    for (double x : {-kWall, length}) {  // end walls
      for (int level = 0; level < kLevels; ++level) {
        const dvec3 lo(x, level * kLevelHeight, -half_width_ - kWall);
        Builder w(lo);
        w.box(lo, {x + kWall, lo.y + kLevelHeight, half_width_ + kWall});
        add(w, lo, "wall");
      }
    }
  }

  Rng rng_;
  uint64_t target_;
  uint64_t triangles_ = 0;
  double q_ = 1.0;
  int nz_ = 2;
  double half_width_ = 0;
  Scene scene_;
};

}  // namespace

Scene generate_plant(const PlantParams& p) {
  if (!(p.millions >= kMinMillions && p.millions <= kMaxMillions))
    throw InputError("plant: millions of triangles must be " + std::to_string(kMinMillions).substr(0, 4) + ".." +
                     std::to_string(int(kMaxMillions)) + " (got " + std::to_string(p.millions) + ")");
  return Generator(p).run();
}

}  // namespace occ::plant
