// Making scenes: glTF 2.0 files (.gltf/.glb), a procedural city, and grid layouts of copies of
// an asset. Every failure throws InputError naming the file and the node/mesh/accessor at fault.
#pragma once
#include <string>

#include "common/scene.hpp"

namespace occ {

// Loads all scenes' node trees (default scene if set, else scene 0) with node transforms and
// mesh instancing. Triangle primitives only (mode 4); other modes are counted and reported,
// not drawn. Missing normals are computed.
Scene load_gltf(const std::string& path);

struct CityParams {
  int blocks_x = 10;         // city blocks along x
  int blocks_z = 10;         // city blocks along z
  int buildings_per_block = 4;  // per side (n x n buildings per block)
  int floors_max = 12;       // building heights vary 1..floors_max floors
  int detail = 2;            // window subdivision per facade: triangles grow ~ detail^2
  uint32_t seed = 1;
};
// A grid of city blocks with box buildings of varying heights separated by streets: high depth
// complexity at eye height. Triangle count grows with blocks, buildings and detail.
Scene generate_city(const CityParams& p);

// nx x nz copies of asset on a grid, spacing = asset footprint * (1 + gap).
Scene layout_grid(const Scene& asset, int nx, int nz, double gap);

// --scene spec:
//   path.gltf | path.glb                 a glTF file
//   city[:BXxBZ[:N[:F[:D]]]]             generate_city (blocks, buildings/side, max floors, detail)
//   layout:NXxNZ:path                    layout_grid of a glTF asset
//   plant:M                              plant::generate_plant (plant.hpp): an industrial hall of
//                                        about M million triangles (0.01 <= M <= 200, fractions
//                                        allowed), every object its own mesh (no instancing);
//                                        walk:N goes down its central aisle
//   offset:DX,DY,DZ:<spec>               any scene translated by (DX,DY,DZ) (|D| <= 1e9): the object
//                                        transforms (double) move, the meshes (float) do not
// Hard cases (deterministic; Y up; the tests in tests/hard_*.cpp pin cameras on them):
//   hard:walls[:N]   N (default 5, 1..100) zero-thickness walls in the planes x = 10k (y 0..4,
//                    z -6..6) with a door (z -1..1, y 0..2.5); behind each, cubes at x = 10k+4.5,
//                    z = -4.5, -0.5, 3.5 and a 1x5x1 tower at (10k+2, 0, 2.5) rising above it;
//                    an open 3 m box at (-8, 0, -1.5) without its +x face; a zero-thickness
//                    edge-on wall in the plane z = 8 (x 0..10(N+1), y 0..4); a flat ground y = 0
//   hard:span        cubes of 1e-3 .. 1e3 units on a "bench" at y = 1 (x from 0, each 3 sizes
//                    after the last); a 1e-3 part hidden 1e-3 behind a 4e-3 plate at x = -0.01
//                    and one peeking out beside it; a hall 1e5 x 2e4 x 1e5 (floor y = -1) and
//                    four 1e4-unit pillars at (+-3e4, +-3e4)
//   hard:degenerate  meshes of only zero-area triangles (and a single point), a cube with
//                    degenerate triangles inside, two huge triangles (a 2e6 ground at y = 0 and a
//                    backdrop in the plane x = 300), a wall at x = 20..20.2 and a 12x12 field of
//                    2e-3 cubes (sub-pixel) at x = 25..47 behind and beside it
//   hard:exit[:N]    a closed 4 m room (0..4 in x and z, y 0..3, every face, the eye can stand in
//                    it), and in front of its +x face an N x N field (default 16, 2..100) of cubes
//                    1.6 m wide and 1.5..4 m tall on a 2 m grid from x = 6, z = 2 - N: the eye
//                    walking out of the room through its wall (the occlusion switch's worst case:
//                    nothing it saw last frame hides the field)
// Throws InputError for unknown specs and bad numbers.
Scene load_scene(const std::string& spec);

}  // namespace occ
