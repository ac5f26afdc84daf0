// Scenes the unit tests build in code (no files): a grid of unit cubes and small city parameters.
#pragma once
#include <string>

#include <glm/gtc/matrix_transform.hpp>

#include "common/error.hpp"
#include "common/scene/scene.hpp"
#include "common/scene/scene_io.hpp"

namespace occtest {

// The message of the InputError thrown by load_scene(spec), or "" if none.
inline std::string spec_error(const std::string& spec) {
  try {
    occ::load_scene(spec);
  } catch (const occ::InputError& e) {
    return e.what();
  }
  return "";
}

// Unit cubes [0,1]^3 on an n x n grid in the xz plane (spacing apart), one object each, all
// sharing mesh 0.
inline occ::Scene cube_grid(int n, double spacing) {
  occ::Scene s;
  occ::Mesh cube;
  for (int i = 0; i < 8; ++i) cube.positions.push_back({float(i & 1), float((i >> 1) & 1), float((i >> 2) & 1)});
  cube.indices = {0, 1, 3, 0, 3, 2, 4, 6, 7, 4, 7, 5, 0, 4, 5, 0, 5, 1, 2, 3, 7, 2, 7, 6, 0, 2, 6, 0, 6, 4, 1, 5, 7, 1, 7, 3};
  occ::compute_normals(cube);
  s.meshes.push_back(cube);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      s.objects.push_back({0, glm::translate(glm::dmat4(1.0), glm::dvec3(spacing * i, 0, spacing * j)), ""});
  return s;
}

// generate_city's parameters: blocks_x x blocks_z blocks of buildings x buildings buildings of at
// most `floors` floors, facades subdivided `detail` times (the fields of a "city:" spec).
inline occ::CityParams city_params(int blocks_x, int blocks_z, int buildings, int floors, int detail,
                                   uint32_t seed = 1) {
  occ::CityParams p;
  p.blocks_x = blocks_x;
  p.blocks_z = blocks_z;
  p.buildings_per_block = buildings;
  p.floors_max = floors;
  p.detail = detail;
  p.seed = seed;
  return p;
}

}  // namespace occtest
