// The mesh simplifier behind the leaf LODs and HLODs (lod_build.cpp). Internal to occ_common:
// nothing outside common/lod/ includes it.
//
// meshopt_simplify on a position-welded copy (normal/colour seams do not block collapses), borders
// locked, falling back to meshopt_simplifySloppy when topology stops it (disjoint buildings);
// each output vertex takes the normal of the original vertex whose normal best matches the new
// face (creases stay sharp) and, for HLOD input, that vertex's object (its colour).
#pragma once
#include <cstddef>
#include <cstdint>

#include "common/lod/lod_data.hpp"

namespace occ {

// Simplifies `in` towards target_indices (a multiple of 3). Returns the new mesh (same origin)
// with error = in.error + the simplifier's absolute error (never less than how far the bounding
// box moved).
LodMesh simplify_lod_mesh(const LodMesh& in, size_t target_indices);

// The index count to aim for: `ratio` of the triangles of `index_count` indices, at least
// min_triangles.
size_t simplify_target(size_t index_count, float ratio, uint32_t min_triangles);

}  // namespace occ
