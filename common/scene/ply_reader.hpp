// PLY files (Stanford polygon format: ASCII, binary little- and big-endian) as Scenes, read by
// our own parser straight from a memory mapping. Every failure throws InputError naming the file
// and the header line, element row or byte at fault.
#pragma once
#include <string>

#include "common/scene/scene.hpp"

namespace occ {

// One mesh, one object (identity transform), named after the file. The `vertex` element's x, y, z
// (any numeric type) make the positions; nx, ny, nz the normals when all three are present (else
// the mesh is shaded flat, Mesh::flat, as glTF does without NORMAL); red, green, blue and alpha
// (uchar 0..255, or float/double 0..1) the vertex colours. The `face` element's list property
// vertex_indices (or vertex_index) holds polygons of 3 or more vertices, split into triangle fans
// (winding kept). Other elements and properties are read past. Without vertex colours the mesh
// has no material (a per-object colour, double-sided, as generated scenes); with them a white
// opaque double-sided material. Zero-area and repeated triangles are left out as glTF's are.
// Rejected: a header that is not PLY 1.0, an element or property that cannot be read, a file
// that ends before its header says (truncated; an ASCII file must end with a newline, so that a
// number cut short is seen), bytes other than whitespace after the last
// element, an index out of range, a face of fewer than 3 vertices, a value that is not finite.
Scene load_ply(const std::string& path);

// Whether path ends in .ply, in any case.
bool is_ply_path(const std::string& path);

}  // namespace occ
