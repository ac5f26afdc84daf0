// The generated structures of the limit benchmarks (structures.hpp).
#include "common/scene/structures.hpp"

#include <cmath>
#include <glm/gtc/matrix_transform.hpp>
#include <string>

#include "common/scene/scene_shapes.hpp"

namespace occ {
namespace {

using glm::dmat4;
using glm::dvec3;

constexpr double kPi = 3.14159265358979323846;

void place(Scene& s, uint32_t mesh, const dmat4& transform, std::string name) {
  s.objects.push_back(Object{mesh, transform, std::move(name)});
}

// A closed prism along +x from 0 to 1 of radius 1 with `sides` sides (caps included): bars,
// pipes, columns. Smooth normals on the sides.
Mesh prism_mesh(const std::string& name, int sides) {
  Mesh m;
  m.name = name;
  for (int end = 0; end < 2; ++end)
    for (int i = 0; i < sides; ++i) {
      const double a = 2.0 * kPi * i / sides;
      const glm::vec3 dir(0, float(std::cos(a)), float(std::sin(a)));
      m.positions.push_back(glm::vec3(float(end), 0, 0) + dir);
      m.normals.push_back(dir);
    }
  const auto n = uint32_t(sides);
  for (uint32_t i = 0; i < n; ++i) {
    const uint32_t j = (i + 1) % n;
    m.indices.insert(m.indices.end(), {i, j, n + j, i, n + j, n + i});
  }
  for (int end = 0; end < 2; ++end) {  // caps: a fan over each ring, facing -x and +x
    const auto base = uint32_t(m.positions.size());
    for (int i = 0; i < sides; ++i) {
      m.positions.push_back(m.positions[size_t(end) * n + size_t(i)]);
      m.normals.push_back(glm::vec3(end ? 1.0f : -1.0f, 0, 0));
    }
    for (uint32_t i = 1; i + 1 < n; ++i)
      if (end) m.indices.insert(m.indices.end(), {base, base + i, base + i + 1});
      else m.indices.insert(m.indices.end(), {base, base + i + 1, base + i});
  }
  return m;
}

// Appends `m` moved by `t` (positions and normals) to `to`.
void append(Mesh& to, const Mesh& m, const glm::mat4& t) {
  const auto base = uint32_t(to.positions.size());
  const glm::mat3 n = glm::transpose(glm::inverse(glm::mat3(t)));
  for (size_t i = 0; i < m.positions.size(); ++i) {
    to.positions.push_back(glm::vec3(t * glm::vec4(m.positions[i], 1.0f)));
    to.normals.push_back(glm::normalize(n * m.normals[i]));
  }
  for (uint32_t i : m.indices) to.indices.push_back(base + i);
}

// x -> the given axis (0 x, 1 y, 2 z) for the prisms.
dmat4 axis_x_to(int axis) {
  if (axis == 1) return glm::rotate(dmat4(1.0), kPi / 2, dvec3(0, 0, 1));
  if (axis == 2) return glm::rotate(dmat4(1.0), -kPi / 2, dvec3(0, 1, 0));
  return dmat4(1.0);
}

// A prism of radius r from `from` along `axis` for `length`, in frame f.
dmat4 bar(const dmat4& f, dvec3 from, int axis, double length, double r) {
  return f * glm::translate(dmat4(1.0), from) * axis_x_to(axis) * glm::scale(dmat4(1.0), dvec3(length, r, r));
}

// The unit cube [0,1]^3 stretched over [lo, hi] in frame f.
dmat4 block(const dmat4& f, dvec3 lo, dvec3 hi) {
  return f * glm::translate(dmat4(1.0), lo) * glm::scale(dmat4(1.0), hi - lo);
}

// A rectangular loop of bars in the y-z plane at x = 0 around [y0,y1] x [z0,z1] (a stirrup or
// a tie) as one mesh: four octagonal bars of radius r.
Mesh loop_mesh(const std::string& name, const Mesh& prism, double y0, double y1, double z0, double z1, double r) {
  Mesh m;
  m.name = name;
  append(m, prism, glm::mat4(bar(dmat4(1.0), {0, y0, z0}, 2, z1 - z0, r)));
  append(m, prism, glm::mat4(bar(dmat4(1.0), {0, y1, z0}, 2, z1 - z0, r)));
  append(m, prism, glm::mat4(bar(dmat4(1.0), {0, y0, z0}, 1, y1 - y0, r)));
  append(m, prism, glm::mat4(bar(dmat4(1.0), {0, y0, z1}, 1, y1 - y0, r)));
  return m;
}

}  // namespace

// bridge (structures.hpp): concrete members along an arc, their reinforcement inside them.
Scene bridge(int spans) {
  check_range("bridge", "spans", spans, 1, 200);
  Scene s;
  const uint32_t cube = add_mesh(s, box_mesh("unit cube", {0, 0, 0}, {1, 1, 1}));
  const Mesh octagon = prism_mesh("bar", 8);
  const uint32_t rod = add_mesh(s, octagon);
  // Stirrups of the girders (section 1.2 x 1.5, 5 cm cover) and ties of the piers (1.2 x 4).
  const uint32_t stirrup = add_mesh(s, loop_mesh("stirrup", octagon, 0.05, 1.45, 0.05, 1.15, 0.008));
  Mesh tie_loop;  // horizontal, around the pier's section (x -0.6..0.6, z -2..2)
  tie_loop.name = "tie";
  for (int i = 0; i < 2; ++i) {
    append(tie_loop, octagon, glm::mat4(bar(dmat4(1.0), {i ? 0.55 : -0.55, 0, -1.95}, 2, 3.9, 0.008)));
    append(tie_loop, octagon, glm::mat4(bar(dmat4(1.0), {-0.55, 0, i ? 1.95 : -1.95}, 0, 1.1, 0.008)));
  }
  const uint32_t tie = add_mesh(s, std::move(tie_loop));
  const double radius = 120, length = 30, rise = 0.02;
  const double turn = length / radius;
  auto on_arc = [&](int k) {
    const double a = turn * k;
    return dvec3(radius * std::sin(a), rise * length * k, radius * (1.0 - std::cos(a)));
  };
  Aabb plan;  // the ground: the deck's plan and 20 m around it
  for (int k = 0; k <= spans; ++k) plan.grow(on_arc(k));
  Mesh ground;
  ground.name = "ground";
  add_grid(ground, glm::vec3(plan.min.x - 20, 0, plan.min.z - 20), {0, 0, float(plan.extent().z + 40)},
           {float(plan.extent().x + 40), 0, 0}, 1, 1);
  place(s, add_mesh(s, std::move(ground)), dmat4(1.0), "ground");
  for (int k = 0; k < spans; ++k) {
    const dvec3 p = on_arc(k), q = on_arc(k + 1);
    const double yaw = std::atan2(q.z - p.z, q.x - p.x);
    const dmat4 level = glm::rotate(glm::translate(dmat4(1.0), p), -yaw, dvec3(0, 1, 0));
    const dmat4 deck = glm::rotate(level, std::atan(rise), dvec3(0, 0, 1));
    const double span = glm::length(dvec3(q.x - p.x, 0, q.z - p.z)) * std::sqrt(1.0 + rise * rise);
    const std::string name = "span " + std::to_string(k);
    // Concrete.
    place(s, cube, block(deck, {0, 8.0, -6}, {span, 8.3, 6}), name + " deck");
    for (int side = 0; side < 2; ++side) {
      const double z0 = side ? 2.5 : -3.7, pz = side ? 5.8 : -6.0;
      place(s, cube, block(deck, {0, 6.5, z0}, {span, 8.0, z0 + 1.2}), name + " girder " + std::to_string(side));
      place(s, cube, block(deck, {0, 8.3, pz}, {span, 9.3, pz + 0.2}), name + " parapet " + std::to_string(side));
    }
    const double pier_top = 5.9 + p.y;
    place(s, cube, block(level, {-0.6, 0, -2}, {0.6, pier_top, 2}), name + " pier");
    place(s, cube, block(level, {-1.2, pier_top, -4.5}, {1.2, 6.5 + p.y, 4.5}), name + " pier cap");
    // The deck's bars: two layers along and across it.
    for (int layer = 0; layer < 2; ++layer) {
      const double y = layer ? 8.25 : 8.05;
      for (int i = 0; i < 48; ++i)
        place(s, rod, bar(deck, {0.05, y, -5.875 + 0.25 * i}, 0, span - 0.1, 0.0125),
              name + " deck bar " + std::to_string(layer) + "." + std::to_string(i));
      for (int i = 0; i * 0.3 + 0.15 < span - 0.05; ++i)
        place(s, rod, bar(deck, {0.15 + 0.3 * i, y, -5.95}, 2, 11.9, 0.0125),
              name + " deck cross bar " + std::to_string(layer) + "." + std::to_string(i));
    }
    // The girders' bars (3 x 3) and a stirrup every 0.3 m.
    for (int side = 0; side < 2; ++side) {
      const double z0 = side ? 2.5 : -3.7;
      const std::string g = name + " girder " + std::to_string(side);
      for (int i = 0; i < 9; ++i)
        place(s, rod, bar(deck, {0.05, 6.55 + 0.7 * (i / 3), z0 + 0.05 + 0.55 * (i % 3)}, 0, span - 0.1, 0.016),
              g + " bar " + std::to_string(i));
      for (int i = 0; i * 0.3 + 0.15 < span - 0.05; ++i)
        place(s, stirrup, deck * glm::translate(dmat4(1.0), dvec3(0.15 + 0.3 * i, 6.5, z0)),
              g + " stirrup " + std::to_string(i));
    }
    // The pier's bars up its faces and a tie every 0.5 m.
    for (int i = 0; i < 22; ++i)
      place(s, rod, bar(level, {i % 2 ? 0.55 : -0.55, 0.05, -1.95 + 3.9 * (i / 2) / 10.0}, 1, pier_top - 0.1, 0.02),
            name + " pier bar " + std::to_string(i));
    for (int i = 0; i * 0.5 + 0.25 < pier_top - 0.05; ++i)
      place(s, tie, level * glm::translate(dmat4(1.0), dvec3(0, 0.25 + 0.5 * i, 0)), name + " pier tie " + std::to_string(i));
  }
  return s;
}

// office (structures.hpp): rooms behind cross walls, storey above storey.
Scene office(int bays) {
  check_range("office", "bays", bays, 1, 100);
  Scene s;
  Material glass;
  glass.name = "glass";
  glass.base_color = {0.55f, 0.75f, 0.85f, 0.3f};
  glass.alpha_mode = AlphaMode::Blend;
  glass.double_sided = true;
  s.materials.push_back(glass);
  const uint32_t cube = add_mesh(s, box_mesh("unit cube", {0, 0, 0}, {1, 1, 1}));
  Mesh pane = box_mesh("glass pane", {0, 0, 0}, {1, 1, 1});
  pane.material = 0;
  const uint32_t glass_cube = add_mesh(s, std::move(pane));
  const Mesh box = box_mesh("box", {0, 0, 0}, {1, 1, 1});
  auto furniture = [&](const std::string& name, std::initializer_list<std::pair<dvec3, dvec3>> parts) {
    Mesh m;
    m.name = name;
    for (const auto& [lo, hi] : parts) append(m, box, glm::mat4(block(dmat4(1.0), lo, hi)));
    return add_mesh(s, std::move(m));
  };
  const uint32_t desk = furniture("desk", {{{0, 0.72, 0}, {1.6, 0.75, 0.8}}, {{0.02, 0, 0.02}, {0.07, 0.72, 0.07}},
                                           {{1.53, 0, 0.02}, {1.58, 0.72, 0.07}}, {{0.02, 0, 0.73}, {0.07, 0.72, 0.78}},
                                           {{1.53, 0, 0.73}, {1.58, 0.72, 0.78}}});
  const uint32_t chair = furniture("chair", {{{0, 0.45, 0}, {0.5, 0.5, 0.5}}, {{0, 0.5, 0.45}, {0.5, 1.0, 0.5}},
                                             {{0.22, 0.05, 0.22}, {0.28, 0.45, 0.28}}, {{0, 0, 0.22}, {0.5, 0.05, 0.28}},
                                             {{0.22, 0, 0}, {0.28, 0.05, 0.5}}});
  const uint32_t screen = furniture("screen", {{{0, 1.0, 0}, {0.6, 1.38, 0.03}}, {{0.27, 0.75, 0}, {0.33, 1.0, 0.15}}});
  const uint32_t cabinet = furniture("cabinet", {{{0, 0, 0}, {0.9, 1.9, 0.45}}, {{0.05, 0.1, 0.45}, {0.85, 0.6, 0.47}},
                                                 {{0.05, 0.7, 0.45}, {0.85, 1.2, 0.47}},
                                                 {{0.05, 1.3, 0.45}, {0.85, 1.8, 0.47}}});
  const double bay = 6, storey = 3.5, half = 9;
  const double length = bay * bays;
  for (int st = 0; st < 3; ++st) {
    const double y0 = storey * st, y1 = y0 + storey - 0.2;
    const std::string level = "storey " + std::to_string(st);
    for (int k = 0; k < bays; ++k) {
      const double x0 = bay * k, x1 = x0 + bay;
      const std::string room = level + " bay " + std::to_string(k);
      place(s, cube, block(dmat4(1.0), {x0, y0 - 0.2, -half}, {x1, y0, half}), room + " floor");
      if (st == 2) place(s, cube, block(dmat4(1.0), {x0, y1, -half}, {x1, y1 + 0.3, half}), room + " roof");
      for (int side = 0; side < 2; ++side) {  // outer walls with a window band of glass
        const double z0 = side ? half : -half - 0.25;
        place(s, cube, block(dmat4(1.0), {x0, y0, z0}, {x1, y0 + 0.9, z0 + 0.25}), room + " parapet " + std::to_string(side));
        place(s, glass_cube, block(dmat4(1.0), {x0, y0 + 0.9, z0 + 0.1}, {x1, y0 + 2.6, z0 + 0.15}),
              room + " window " + std::to_string(side));
        place(s, cube, block(dmat4(1.0), {x0, y0 + 2.6, z0}, {x1, y1, z0 + 0.25}), room + " lintel " + std::to_string(side));
      }
      // The cross wall at the bay's start (the building's end walls solid): two doors, every
      // third one glass.
      const bool glazed = k > 0 && k % 3 == 0;
      const uint32_t wall = glazed ? glass_cube : cube;
      const double w0 = x0 - 0.1, w1 = x0 + 0.1;
      if (k == 0) {
        place(s, cube, block(dmat4(1.0), {w0 - 0.15, y0, -half}, {w1 - 0.15, y1, half}), room + " end wall");
      } else {
        const double z[5] = {-half, -6, -5, 5, 6};
        for (int i = 0; i < 3; ++i) {
          const double za = i == 0 ? z[0] : i == 1 ? z[2] : z[4], zb = i == 0 ? z[1] : i == 1 ? z[3] : half;
          place(s, wall, block(dmat4(1.0), {w0, y0, za}, {w1, y1, zb}), room + " cross wall " + std::to_string(i));
        }
        for (int i = 0; i < 2; ++i)
          place(s, wall, block(dmat4(1.0), {w0, y0 + 2.1, i ? 5.0 : -6.0}, {w1, y1, i ? 6.0 : -5.0}),
                room + " door head " + std::to_string(i));
      }
      // Furniture: two rows of three desks each side of the aisle, a chair and a screen at each,
      // cabinets along the outer walls.
      for (int side = 0; side < 2; ++side)
        for (int i = 0; i < 3; ++i) {
          const double dx = x0 + 0.6 + 1.7 * i, dz = side ? 2.5 : -3.3, cz = side ? 3.4 : -3.9;
          const std::string at = room + " desk " + std::to_string(side) + "." + std::to_string(i);
          place(s, desk, glm::translate(dmat4(1.0), dvec3(dx, y0, dz)), at);
          place(s, chair, glm::translate(dmat4(1.0), dvec3(dx + 0.55, y0, cz)), at + " chair");
          place(s, screen, glm::translate(dmat4(1.0), dvec3(dx + 0.5, y0, dz + (side ? 0.1 : 0.55))), at + " screen");
          place(s, desk, glm::translate(dmat4(1.0), dvec3(dx, y0, side ? 5.4 : -6.2)), at + " back desk");
        }
      for (int side = 0; side < 2; ++side)
        for (int i = 0; i < 2; ++i)
          place(s, cabinet, glm::translate(dmat4(1.0), dvec3(x0 + 1.0 + 3.0 * i, y0, side ? half - 0.5 : -half + 0.05)),
                room + " cabinet " + std::to_string(side) + "." + std::to_string(i));
    }
    place(s, cube, block(dmat4(1.0), {length - 0.05, y0, -half}, {length + 0.15, y1, half}), level + " end wall");
  }
  return s;
}

constexpr int kRackModules = 8;       // pipes: modules in a rack along x
constexpr double kRackSpacing = 14.0;  // pipes: racks side by side along z

// pipes (structures.hpp): a pipe rack of steel frames, pipes, branches and cable trays.
Scene pipes(int modules) {
  check_range("pipes", "modules", modules, 1, 100);
  Scene s;
  const uint32_t cube = add_mesh(s, box_mesh("unit cube", {0, 0, 0}, {1, 1, 1}));
  const uint32_t tube = add_mesh(s, prism_mesh("pipe", 24));
  const uint32_t flange = add_mesh(s, prism_mesh("flange", 24));
  Mesh bend;  // a 90-degree elbow of unit bend radius and tube radius 0.5, from +x turning to -y
  bend.name = "elbow";
  const Mesh ring = prism_mesh("ring", 16);
  for (int i = 0; i < 6; ++i) {
    const double a0 = kPi / 2 * i / 6, a1 = kPi / 2 * (i + 1) / 6;
    const double chord = 2.0 * std::sin((a1 - a0) / 2);
    const dmat4 t = glm::translate(dmat4(1.0), dvec3(std::sin(a0), std::cos(a0) - 1.0, 0)) *
                    glm::rotate(dmat4(1.0), -(a0 + a1) / 2, dvec3(0, 0, 1)) *
                    glm::scale(dmat4(1.0), dvec3(chord, 0.5, 0.5));
    append(bend, ring, glm::mat4(t));
  }
  const uint32_t elbow = add_mesh(s, std::move(bend));
  Mesh tray_profile;  // an open U along x, 0.6 wide, 0.1 deep
  tray_profile.name = "cable tray";
  const Mesh box = box_mesh("box", {0, 0, 0}, {1, 1, 1});
  append(tray_profile, box, glm::mat4(block(dmat4(1.0), {0, 0, 0}, {1, 0.005, 0.6})));
  append(tray_profile, box, glm::mat4(block(dmat4(1.0), {0, 0, 0}, {1, 0.1, 0.005})));
  append(tray_profile, box, glm::mat4(block(dmat4(1.0), {0, 0, 0.595}, {1, 0.1, 0.6})));
  const uint32_t tray = add_mesh(s, std::move(tray_profile));
  const double module = 6, levels[3] = {4, 7, 10};
  for (int k = 0; k < modules; ++k) {
    const double x0 = module * (k % kRackModules);
    const dmat4 id = glm::translate(dmat4(1.0), dvec3(0, 0, kRackSpacing * (k / kRackModules)));
    const std::string m = "module " + std::to_string(k);
    for (int c = 0; c < 2; ++c)  // a frame: two columns, three cross beams
      place(s, cube, block(id, {x0, 0, c ? 3.0 : -3.3}, {x0 + 0.3, 11, c ? 3.3 : -3.0}), m + " column " + std::to_string(c));
    for (double y : levels)
      place(s, cube, block(id, {x0, y - 0.3, -3.3}, {x0 + 0.3, y, 3.3}), m + " beam " + std::to_string(int(y)));
    for (int c = 0; c < 2; ++c)
      place(s, cube, block(id, {x0, 10.7, c ? 3.0 : -3.3}, {x0 + module, 11, c ? 3.3 : -3.0}),
            m + " girder " + std::to_string(c));
    for (int l = 0; l < 3; ++l)
      for (int i = 0; i < 12; ++i) {  // pipes on the beams, 0.05-0.2 m radius
        const double r = 0.05 + 0.15 * double((i * 7 + l * 3) % 5) / 4.0;
        const dvec3 at(x0, levels[l] + r, -2.9 + 0.5 * i);
        const std::string p = m + " pipe " + std::to_string(l) + "." + std::to_string(i);
        place(s, tube, bar(id, at, 0, module, r), p);
        place(s, flange, bar(id, at - dvec3(0.04, 0, 0), 0, 0.08, r * 1.4), p + " flange");
      }
    for (int b = 0; b < 3; ++b) {  // branches dropping from the lowest level: elbow, drop, valve
      const int i = (k * 5 + b * 4) % 12;
      const double r = 0.05 + 0.15 * double((i * 7) % 5) / 4.0;
      const double x = x0 + 1.0 + 1.6 * b, z = -2.9 + 0.5 * i;
      const std::string p = m + " branch " + std::to_string(b);
      place(s, elbow, glm::translate(id, dvec3(x - 4 * r, levels[0] - 0.5 + r, z)) * glm::scale(dmat4(1.0), dvec3(2 * r)), p + " elbow");
      place(s, tube, bar(id, {x - 2 * r, 1.0, z}, 1, levels[0] - 1.5 - r, r), p + " drop");
      place(s, cube, block(id, {x - 3 * r, 1.6, z - r}, {x - r, 1.6 + 3 * r, z + r}), p + " valve");
      place(s, flange, bar(id, {x - 2 * r, 1.6 + 3 * r, z}, 1, 0.3, 2.5 * r), p + " handwheel");
    }
    for (int t = 0; t < 2; ++t)
      place(s, tray, glm::translate(id, dvec3(x0, 11 + 0.05, t ? 0.4 : -1.0)) * glm::scale(dmat4(1.0), dvec3(module, 1, 1)),
            m + " cable tray " + std::to_string(t));
  }
  Mesh ground;
  ground.name = "ground";
  const int racks = (modules + kRackModules - 1) / kRackModules;
  add_grid(ground, {-10, 0, -10}, {0, 0, float(kRackSpacing * racks + 8)}, {float(module * kRackModules + 20), 0, 0}, 1, 1);
  place(s, add_mesh(s, std::move(ground)), dmat4(1.0), "ground");
  return s;
}

}  // namespace occ
