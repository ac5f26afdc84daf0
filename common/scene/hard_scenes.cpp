// The hard-case scenes (hard_scenes.hpp).
#include "common/scene/hard_scenes.hpp"

#include <cmath>
#include <glm/gtc/matrix_transform.hpp>
#include <string>

#include "common/scene/scene_shapes.hpp"

namespace occ {
namespace {

void place(Scene& s, uint32_t mesh, const glm::dvec3& at, const std::string& name,
           const glm::dvec3& scale = glm::dvec3(1.0)) {
  s.objects.push_back(Object{mesh, glm::scale(glm::translate(glm::dmat4(1.0), at), scale), name});
}

}  // namespace

// hard:walls (layout in hard_scenes.hpp): zero-thickness walls with doors, cubes behind each wall,
// an open box to stand in, an edge-on wall and a flat ground.
Scene hard_walls(int walls) {
  Scene s;
  const uint32_t ground = add_mesh(s, Mesh{});
  add_grid(s.meshes[ground], {-20, 0, -20}, {0, 0, 40}, {20.0f + 10.0f * float(walls + 1), 0, 0}, 1, 1);
  s.meshes[ground].name = "ground (flat box)";
  // A wall in the plane x = 0: y in [0, 4], z in [-6, 6], a door z in [-1, 1], y in [0, 2.5].
  Mesh wall;
  wall.name = "wall (zero thickness)";
  add_grid(wall, {0, 0, -6}, {0, 0, 5}, {0, 4, 0}, 1, 1);
  add_grid(wall, {0, 0, 1}, {0, 0, 5}, {0, 4, 0}, 1, 1);
  add_grid(wall, {0, 2.5f, -1}, {0, 0, 2}, {0, 1.5f, 0}, 1, 1);
  const uint32_t wall_mesh = add_mesh(s, std::move(wall));
  const uint32_t cube = add_mesh(s, box_mesh("unit cube", {0, 0, 0}, {1, 1, 1}));
  const uint32_t open_box = add_mesh(s, box_mesh("open box", {0, 0, 0}, {3, 3, 3}, true));
  Mesh edge;
  edge.name = "edge-on wall";
  add_grid(edge, {0, 0, 0}, {0, 4, 0}, {10.0f * float(walls + 1), 0, 0}, 1, 1);  // plane z = 0
  const uint32_t edge_mesh = add_mesh(s, std::move(edge));

  s.objects.push_back(Object{ground, glm::dmat4(1.0), "ground"});
  place(s, open_box, {-8, 0, -1.5}, "open box");
  place(s, edge_mesh, {0, 0, 8}, "edge-on wall");
  for (int k = 1; k <= walls; ++k) {
    const std::string w = "wall " + std::to_string(k);
    place(s, wall_mesh, {10.0 * k, 0, 0}, w);
    for (int c = 0; c < 3; ++c)
      place(s, cube, {10.0 * k + 4.5, 0, -4.5 + 4.0 * c}, w + " cube " + std::to_string(c));
    place(s, cube, {10.0 * k + 2.0, 0, 2.5}, w + " tower", {1, 5, 1});  // above the wall: partly visible
  }
  return s;
}

// hard:exit (layout in hard_scenes.hpp): a closed room and a dense field of cubes outside it.
Scene hard_exit(int n) {
  Scene s;
  const uint32_t ground = add_mesh(s, Mesh{});
  add_grid(s.meshes[ground], {-2, 0, float(-n - 2)}, {0, 0, float(2 * n + 8)}, {float(2 * n + 12), 0, 0}, 1, 1);
  s.meshes[ground].name = "ground";
  s.objects.push_back(Object{ground, glm::dmat4(1.0), "ground"});
  place(s, add_mesh(s, box_mesh("room", {0, 0, 0}, {4, 3, 4})), {0, 0, 0}, "room");
  const uint32_t cube = add_mesh(s, box_mesh("cube", {0, 0, 0}, {1.6f, 1, 1.6f}));
  for (int i = 0; i < n; ++i)
    for (int k = 0; k < n; ++k) {
      const double height = 1.5 + 2.5 * double((i * 7 + k * 13) % 11) / 10.0;
      place(s, cube, {6.0 + 2.0 * i, 0, 2.0 - n + 2.0 * k}, "cube " + std::to_string(i) + "," + std::to_string(k),
            {1, height, 1});
    }
  return s;
}

// hard:span: parts from 1e-3 to 1e3 units on a bench, a tiny part behind a tiny plate, inside a
// hall 1e5 wide (inward faces), with 1e4-unit pillars.
Scene hard_span() {
  Scene s;
  const uint32_t cube = add_mesh(s, box_mesh("unit cube", {0, 0, 0}, {1, 1, 1}));
  const uint32_t hall = add_mesh(s, box_mesh("hall", {-0.5f, 0, -0.5f}, {0.5f, 1, 0.5f}));
  place(s, hall, {0, -1, 0}, "hall", {1e5, 2e4, 1e5});
  double x = 0;
  for (int e = -3; e <= 3; ++e) {  // sizes 1e-3 .. 1e3, each on the bench at y = 1
    const double size = std::pow(10.0, e);
    place(s, cube, {x, 1.0, -0.5 * size}, "part 1e" + std::to_string(e), glm::dvec3(size));
    x += 3.0 * size;
  }
  // A 1e-3 part hidden 1e-3 behind a 4e-3 plate (seen from -x), and one peeking out beside it.
  place(s, cube, {-0.01, 1.0, -0.002}, "tiny plate", {1e-4, 4e-3, 4e-3});
  place(s, cube, {-0.0085, 1.0015, -0.0005}, "tiny hidden part", glm::dvec3(1e-3));
  place(s, cube, {-0.0085, 1.0015, 0.0025}, "tiny peeking part", glm::dvec3(1e-3));
  for (int i = 0; i < 4; ++i)
    place(s, cube, {(i % 2 ? 3e4 : -3e4) - 5e2, -1, (i / 2 ? 3e4 : -3e4) - 5e2}, "pillar " + std::to_string(i),
          {1e3, 1e4, 1e3});
  return s;
}

// hard:degenerate: meshes of zero-area triangles (repeated indices, collinear and coincident
// vertices), a cube with degenerate triangles inside it, two huge triangles (1e6), and a field of
// sub-pixel cubes (2e-3) partly behind a wall.
Scene hard_degenerate() {
  Scene s;
  Mesh degenerate;
  degenerate.name = "degenerate triangles only";
  degenerate.positions = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {1, 1, 0}, {1, 1, 0}};
  degenerate.indices = {0, 0, 1, 0, 1, 2, 3, 4, 3, 3, 3, 3, 0, 2, 1, 4, 4, 0};
  degenerate.normals.assign(degenerate.positions.size(), {0, 0, 1});
  const uint32_t degenerate_mesh = add_mesh(s, std::move(degenerate));
  Mesh point;
  point.name = "a single point";
  point.positions = {{0, 0, 0}};
  point.normals = {{0, 1, 0}};
  point.indices = {0, 0, 0};
  const uint32_t point_mesh = add_mesh(s, std::move(point));
  Mesh mixed = box_mesh("cube with degenerate triangles", {0, 0, 0}, {1, 1, 1});
  const auto base = uint32_t(mixed.positions.size());
  mixed.positions.insert(mixed.positions.end(), {{0.5f, 0.5f, 0.5f}, {0.5f, 0.5f, 0.5f}, {0.2f, 0.5f, 0.5f}});
  mixed.normals.insert(mixed.normals.end(), 3, glm::vec3(0, 1, 0));
  mixed.indices.insert(mixed.indices.end(), {base, base + 1, base + 2, 0, 0, 0, 1, 2, 1});
  const uint32_t mixed_mesh = add_mesh(s, std::move(mixed));
  Mesh huge;
  huge.name = "huge triangles";
  huge.positions = {{-1e6f, 0, -1e6f}, {1e6f, 0, -1e6f}, {0, 0, 1e6f},  // ground, y = 0
                    {300, -1e6f, -1e6f}, {300, -1e6f, 1e6f}, {300, 1e6f, 0}};  // backdrop, x = 300
  huge.normals = {{0, 1, 0}, {0, 1, 0}, {0, 1, 0}, {-1, 0, 0}, {-1, 0, 0}, {-1, 0, 0}};
  huge.indices = {0, 2, 1, 3, 4, 5};
  const uint32_t huge_mesh = add_mesh(s, std::move(huge));
  const uint32_t cube = add_mesh(s, box_mesh("unit cube", {0, 0, 0}, {1, 1, 1}));

  s.objects.push_back(Object{huge_mesh, glm::dmat4(1.0), "huge triangles"});
  place(s, degenerate_mesh, {5, 1, -2}, "degenerate triangles");
  place(s, point_mesh, {5, 1, 2}, "point");
  place(s, mixed_mesh, {8, 0.01, -0.5}, "cube with degenerate triangles");
  place(s, cube, {20, 0.01, -3}, "wall", {0.2, 3, 3});
  for (int i = 0; i < 12; ++i)
    for (int j = 0; j < 12; ++j)
      place(s, cube, {25.0 + 2.0 * i, 1.0 + 0.1 * j, -6.0 + 1.0 * j}, "sub-pixel " + std::to_string(i * 12 + j),
            glm::dvec3(2e-3));
  return s;
}

// hard:cracks (layout in hard_scenes.hpp): separate meshes that abut or nearly abut, tiny objects
// behind the seams.
Scene hard_cracks(int bays) {
  Scene s;
  const uint32_t cube = add_mesh(s, box_mesh("unit cube", {0, 0, 0}, {1, 1, 1}));
  // Every part its own box mesh in world coordinates (as exports place them: no shared vertices).
  auto part = [&](const std::string& name, glm::dvec3 lo, glm::dvec3 hi) {
    const uint32_t m = add_mesh(s, box_mesh(name, glm::vec3(lo), glm::vec3(hi)));
    s.objects.push_back(Object{m, glm::dmat4(1.0), name});
  };
  const double base_gap[4] = {0.0, 0.0005, 0.002, 0.008};
  for (int k = 0; k < bays; ++k) {
    const double x0 = 8.0 * k, xw = x0 + 8.0, g = base_gap[k % 4];
    const std::string bay = "bay " + std::to_string(k);
    part(bay + " slab", {x0, -0.3, -4}, {xw, 0, 4});
    // The cross wall: four panels along z, seams at z = -2, 0, 2 of width g, 2g, 3g.
    double z = -4;
    for (int j = 0; j < 4; ++j) {
      const double z1 = j < 3 ? -2.0 + 2.0 * j - 0.5 * g * (j + 1) : 4.0;
      const std::string panel = bay + " cross wall panel " + std::to_string(j);
      if (j == 2) {  // split at y = 1.5: a seam across the wall, T-junctions with both neighbours
        part(panel + " lower", {xw, 0, z}, {xw + 0.2, 1.5, z1});
        part(panel + " upper", {xw, 1.5, z}, {xw + 0.2, 3, z1});
      } else {
        part(panel, {xw, 0, z}, {xw + 0.2, 3, z1});
      }
      if (j < 3) z = -2.0 + 2.0 * j + 0.5 * g * (j + 1);
    }
    // Side walls of two panels each, cut at x0 + 3 and x0 + 5 (where the cross wall is not); the
    // one at z = 4 ends on the cross wall's face.
    part(bay + " side wall -z a", {x0, 0, -4.2}, {x0 + 3, 3, -4});
    part(bay + " side wall -z b", {x0 + 3, 0, -4.2}, {xw + 0.2, 3, -4});
    part(bay + " side wall +z a", {x0, 0, 4}, {x0 + 5, 3, 4.2});
    part(bay + " side wall +z b", {x0 + 5, 0, 4}, {xw, 3, 4.2});
    // Behind each seam, in the next bay: 2, 5 and 10 mm cubes at three heights.
    for (int j = 0; j < 3; ++j)
      for (int h = 0; h < 3; ++h) {
        const double size = h == 0 ? 0.002 : h == 1 ? 0.005 : 0.01;
        const glm::dvec3 at(xw + 0.25 + 0.05 * h, 0.5 + 1.0 * h, -2.0 + 2.0 * j - 0.5 * size);
        place(s, cube, at, bay + " behind seam " + std::to_string(j) + " cube " + std::to_string(h), glm::dvec3(size));
      }
    // A field of 3 mm cubes on the floor: sub-pixel beyond a few metres.
    for (int i = 0; i < 6; ++i)
      for (int j = 0; j < 6; ++j)
        place(s, cube, {x0 + 1.0 + 1.1 * i, 0.0, -3.0 + 1.1 * j}, bay + " grain " + std::to_string(i * 6 + j),
              glm::dvec3(0.003));
  }
  return s;
}

}  // namespace occ
