// Layout constants of the procedural city (generate_city in scene_io.hpp), shared with tests.
// Block (i, j) is a square of n x n lots (n = buildings_per_block) of kLot metres, one building
// per lot; blocks are separated by streets kStreet wide; the city is centred on the origin in x/z
// and Y is up. Block (i, j) spans x in [(i - blocks_x/2) * pitch, ... + pitch] (same in z), its
// buildable area is that square minus half a street on each side.
#pragma once
#include "common/math.hpp"
#include "common/scene_io.hpp"

namespace occ::city {

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
