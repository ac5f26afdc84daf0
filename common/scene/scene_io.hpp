// Making scenes: the --scene spec, and the table of contents of the scene sources it names. Every
// failure throws InputError naming the file or spec and the place at fault.
//   gltf_reader.hpp   load_gltf: glTF 2.0 files (.gltf/.glb)
//   model_reader.hpp  load_model: PLY, OBJ, STL, FBX, COLLADA and the other files Assimp reads
//   city.hpp          generate_city: the procedural city
//   layout.hpp        layout_grid: grid layouts of copies of an asset
//   plant.hpp         plant::generate_plant: the procedural industrial plant
//   hard_scenes.hpp   hard_walls, hard_span, hard_degenerate, hard_exit: the hard cases
#pragma once
#include <string>

#include "common/scene/city.hpp"
#include "common/scene/gltf_reader.hpp"
#include "common/scene/hard_scenes.hpp"
#include "common/scene/layout.hpp"
#include "common/scene/scene.hpp"

namespace occ {

// --scene spec:
//   path.gltf | path.glb                 a glTF file
//   path.ply | .obj | .stl | .fbx | .dae | .3ds | .off | ...   a model file (model_reader.hpp)
//   city[:BXxBZ[:N[:F[:D]]]]             generate_city (blocks, buildings/side, max floors, detail)
//   layout:NXxNZ:path                    layout_grid of a glTF asset
//   plant:M                              plant::generate_plant (plant.hpp): an industrial hall of
//                                        about M million triangles (0.01 <= M <= 200, fractions
//                                        allowed), every object its own mesh (no instancing);
//                                        walk:N goes down its central aisle
//   offset:DX,DY,DZ:<spec>               any scene translated by (DX,DY,DZ) (|D| <= 1e9): the object
//                                        transforms (double) move, the meshes (float) do not
// Hard cases (deterministic; Y up; layouts in hard_scenes.hpp; the tests in tests/hard_*.cpp pin
// cameras on them):
//   hard:walls[:N]   N (default 5, 1..100) zero-thickness walls with doors, cubes behind each, an
//                    open box, an edge-on wall and a flat ground
//   hard:span        parts of 1e-3 .. 1e3 units, a tiny part behind a tiny plate, a 1e5 hall
//   hard:degenerate  zero-area triangles, a single point, huge triangles, a sub-pixel field
//   hard:exit[:N]    a closed room and an N x N field (default 16, 2..100) of cubes outside it
//   hard:cracks[:N]  N bays (default 6, 1..50) of walls and slabs as separate meshes with seams of
//                    0 .. 24 mm and T-junctions, mm cubes behind the seams, a sub-pixel field
// Throws InputError for unknown specs and bad numbers.
Scene load_scene(const std::string& spec);

// The axis a scene's data points up (--up): Y as glTF and our scenes, or Z as CAD tools and many
// scans export.
enum class UpAxis : uint8_t { Y, Z };
// Turns a Z-up scene Y-up: every object's transform rotated -90 degrees about X ((x, y, z) ->
// (x, z, -y)); nothing for Y.
void apply_up_axis(Scene& scene, UpAxis up);

}  // namespace occ
