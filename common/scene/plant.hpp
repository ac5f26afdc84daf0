// A procedural industrial plant of unique geometry (--scene plant:M, see scene_io.hpp): every
// object has its own mesh (no instancing), like the paper's power plant and tanker.
//
// Layout (Y up, metres): a hall of kLevels levels of kLevelHeight, bays of kBay x kBay in a grid
// of nx bays along x (x from 0) and nz bays along z (nz even), half of them on each side of a
// central aisle |z| < kAisle / 2 that runs the whole length of the hall at ground level and is
// open up to the roof. The ground floor is at y = 0 and nothing is below it; nx > nz, so the
// generated walk:N (along the longer axis, at eye height 1.7 m, through the centre) goes down the
// aisle. Bays hold columns and beams (I-beams), floor slabs (some missing), tanks, boilers with
// tube banks, heat exchangers, horizontal vessels, pumps, cable trays, railings and runs of pipes
// with elbows; pipes above kAisleClear may cross the aisle. Outer walls and a roof close the hall.
// Solids are closed (pipe runs end in capped flanges, tanks in heads) with outward faces and one
// single-sided material: back faces are culled, as for a CAD export's glTF (doubleSided false).
#pragma once
#include <cstdint>

#include "common/scene/scene.hpp"

namespace occ::plant {

constexpr double kBay = 12.0;          // bay side
constexpr double kAisle = 6.0;         // width of the central aisle (centred on z = 0)
constexpr double kAisleClear = 3.5;    // nothing in the aisle below this height
constexpr double kLevelHeight = 6.0;   // floor to floor
constexpr int kLevels = 4;             // levels (the roof is at kLevels * kLevelHeight)
constexpr double kMinMillions = 0.01;  // limits of M (millions of triangles)
constexpr double kMaxMillions = 200.0;
// Goes into the scene cache key (scene_cache.hpp): bump it whenever generate_plant's output
// changes, or a cache written by the old generator would be used.
constexpr uint32_t kGeneratorVersion = 2;  // 2: single-sided material

struct PlantParams {
  double millions = 1.0;  // target triangle count / 1e6 (the result is within a few %)
  uint64_t seed = 1;
};

// Deterministic for equal params. Throws InputError if millions is outside the limits.
Scene generate_plant(const PlantParams& p);

}  // namespace occ::plant
