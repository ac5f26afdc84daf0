// The procedural city (--scene city[:...], scene_io.hpp): a grid of city blocks with box
// buildings of varying heights separated by streets, and its layout constants (shared with tests).
// Block (i, j) is a square of n x n lots (n = buildings_per_block) of kLot metres, one building
// per lot; blocks are separated by streets kStreet wide; the city is centred on the origin in x/z
// and Y is up. Block (i, j) spans x in [(i - blocks_x/2) * pitch, ... + pitch] (same in z), its
// buildable area is that square minus half a street on each side.
#pragma once
#include <cstdint>

#include "common/math.hpp"
#include "common/scene/scene.hpp"

namespace occ {

struct CityParams {
  int blocks_x = 10;         // city blocks along x
  int blocks_z = 10;         // city blocks along z
  int buildings_per_block = 4;  // per side (n x n buildings per block)
  int floors_max = 12;       // building heights vary 1..floors_max floors
  int detail = 2;            // window subdivision per facade: triangles grow ~ detail^2
  uint32_t seed = 1;
};
// A grid of city blocks with box buildings of varying heights separated by streets: high depth
// complexity at eye height. Triangle count grows with blocks, buildings and detail. Throws
// InputError when a parameter is outside the city:: limits below.
Scene generate_city(const CityParams& p);

}  // namespace occ

namespace occ::city {

// Limits of the city parameters (also enforced on --scene specs).
constexpr int kMaxBlocks = 1000, kMaxBuildings = 64, kMaxFloors = 200, kMaxDetail = 16;

constexpr double kFloorHeight = 3.0;  // metres per floor
constexpr double kLot = 20.0;         // lot side; building footprints are 10..20 m per side
constexpr double kStreet = 12.0;      // street width between blocks

inline double block_pitch(const CityParams& p) { return p.buildings_per_block * kLot + kStreet; }

// World box of the buildable area of block (i, j), up to the tallest possible building.
inline Aabb block_area(const CityParams& p, int i, int j) {
  const double pitch = block_pitch(p);
  const glm::dvec3 min((i - 0.5 * p.blocks_x) * pitch + 0.5 * kStreet, 0.0,
                       (j - 0.5 * p.blocks_z) * pitch + 0.5 * kStreet);
  return Aabb{min, min + glm::dvec3(pitch - kStreet, p.floors_max * kFloorHeight, pitch - kStreet)};
}

}  // namespace occ::city
