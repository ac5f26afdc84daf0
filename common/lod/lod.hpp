// Levels of detail (paper 4.1), the umbrella header. No GL. The parts, each with its design notes:
//   lod_data.hpp    LodParams, LodMesh, LodData: the LOD chains of every leaf, one HLOD per
//                   interior node, their object-space errors (how they are built: lod_build.cpp,
//                   the simplifier lod_simplify.cpp)
//   lod_cache.hpp   the binary cache file (format, LodData::save/load in lod_cache.cpp), its path,
//                   load_or_build_lod
//   lod_select.hpp  the renderable-id space, the screen-space error, LodSelector, lod_benefit
// See also front.hpp (front tracking over the selection) and culling.hpp.
#pragma once
#include "common/lod/lod_cache.hpp"
#include "common/lod/lod_data.hpp"
#include "common/lod/lod_select.hpp"
