// Grid layouts of copies of an asset (--scene layout:NXxNZ:path, scene_io.hpp).
#pragma once
#include "common/scene/scene.hpp"

namespace occ {

constexpr int kMaxLayoutCopies = 1000;  // per axis (also enforced on --scene specs)

// nx x nz copies of asset on a grid, spacing = asset footprint * (1 + gap). Copy (i, j) is the
// asset translated by (i * spacing_x, 0, j * spacing_z); meshes, materials, textures and images
// are shared by all copies. Throws InputError unless 1 <= nx, nz <= kMaxLayoutCopies.
Scene layout_grid(const Scene& asset, int nx, int nz, double gap);

}  // namespace occ
