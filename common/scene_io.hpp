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
// Throws InputError for unknown specs and bad numbers.
Scene load_scene(const std::string& spec);

}  // namespace occ
