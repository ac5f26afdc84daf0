// Writes a loaded scene as glTF 2.0 (FILE.gltf + FILE.bin beside it) so that another renderer can
// draw exactly the geometry occswitch draws, generated scenes (city, layout) included: bench.sh
// hands it to the OpenSceneGraph peer. Geometry only: one mesh per scene mesh (POSITION, NORMAL,
// uint32 indices), one node per object with its matrix (double precision in the JSON), no
// materials. Meshes without triangles, and the objects using them, are left out (they draw
// nothing). Throws InputError when a file cannot be written.
#pragma once
#include <string>

#include "common/scene/scene.hpp"

namespace occ {

void save_gltf(const Scene& scene, const std::string& gltf_path);

}  // namespace occ
