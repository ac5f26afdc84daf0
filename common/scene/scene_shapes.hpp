// Pieces the generated scenes are built from (the city, the hard cases; the plant has its own
// builder): quad grids, boxes, and the range check of a generator's parameters.
#pragma once
#include <string>

#include "common/scene/scene.hpp"

namespace occ {

// Appends `m` to the scene's meshes; returns its index.
uint32_t add_mesh(Scene& s, Mesh m);

// Appends a rows x cols grid of quads spanning origin + [0,1] u + [0,1] v to m, front (CCW) side
// facing cross(u, v), with that normal at every vertex.
void add_grid(Mesh& m, glm::vec3 origin, glm::vec3 u, glm::vec3 v, int rows, int cols);

// A closed axis-aligned box mesh [lo, hi] (6 faces, 12 triangles), optionally without its +x face
// (an open box the camera can stand in and look out of).
Mesh box_mesh(const std::string& name, glm::vec3 lo, glm::vec3 hi, bool open_plus_x = false);

// Throws InputError "<where>: <what> must be lo..hi (got v)" unless lo <= v <= hi.
void check_range(const std::string& where, const char* what, int v, int lo, int hi);

}  // namespace occ
