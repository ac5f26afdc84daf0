// The hard-case scenes (--scene hard:*, scene_io.hpp): small deterministic scenes of the shapes
// occlusion culling gets wrong (zero-thickness walls, extreme sizes, degenerate triangles, the eye
// leaving a closed room). Y up; the tests in tests/hard_*.cpp pin cameras on these layouts, so a
// change here moves their expectations.
#pragma once
#include "common/scene/scene.hpp"

namespace occ {

// hard:walls[:N]: N (>= 1) zero-thickness walls in the planes x = 10k (y 0..4, z -6..6) with a
// door (z -1..1, y 0..2.5); behind each, cubes at x = 10k+4.5, z = -4.5, -0.5, 3.5 and a 1x5x1
// tower at (10k+2, 0, 2.5) rising above it; an open 3 m box at (-8, 0, -1.5) without its +x face;
// a zero-thickness edge-on wall in the plane z = 8 (x 0..10(N+1), y 0..4); a flat ground y = 0.
Scene hard_walls(int walls);

// hard:span: cubes of 1e-3 .. 1e3 units on a "bench" at y = 1 (x from 0, each 3 sizes after the
// last); a 1e-3 part hidden 1e-3 behind a 4e-3 plate at x = -0.01 and one peeking out beside it;
// a hall 1e5 x 2e4 x 1e5 (floor y = -1, inward faces) and four 1e4-unit pillars at (+-3e4, +-3e4).
Scene hard_span();

// hard:degenerate: meshes of only zero-area triangles (repeated indices, collinear and coincident
// vertices, a single point), a cube with degenerate triangles inside, two huge triangles (a 2e6
// ground at y = 0 and a backdrop in the plane x = 300), a wall at x = 20..20.2 and a 12x12 field
// of 2e-3 cubes (sub-pixel) at x = 25..47 behind and beside it.
Scene hard_degenerate();

// hard:exit[:N]: a closed 4 m room (0..4 in x and z, y 0..3, every face, the eye can stand in
// it), and in front of its +x face an n x n field (n >= 2) of cubes 1.6 m wide and 1.5..4 m tall
// on a 2 m grid from x = 6, z = 2 - n: the eye walking out of the room through its wall (the
// occlusion switch's worst case: nothing it saw last frame hides the field).
Scene hard_exit(int n);

// hard:cracks[:N]: cracks between meshes, as real building exports have them, in N (1..50, default 6)
// bays of 8 m along x (bay k: x 8k..8k+8, z -4..4), each a separate mesh per part: a floor slab
// (y -0.3..0, slabs abutting at the bays' ends) with the walls standing on it; a cross wall at its
// +x end (x 8k+8..8k+8.2, y 0..3) of four panels along z with seams at z = -2, 0, 2 of width
// g (j + 1) for seam j, g = 0, 0.5, 2, 8 mm in bays k = 0, 1, 2, 3 (mod 4): 0 to 1.5 pixels at
// 512^2 from 8 m; its third panel split at y = 1.5, and a side wall along z = 4 whose end meets
// the cross wall's face (T-junctions where the vertices do not match); side walls along z = -4 and
// z = 4 of two panels each, cut where the cross wall's panels are not; right behind every seam,
// in the next bay, cubes of 2, 5 and 10 mm at y = 0.5, 1.5, 2.5, and a field of 3 mm cubes on each
// floor: objects seen, if at all, through a crack or smaller than a pixel.
Scene hard_cracks(int bays);

}  // namespace occ
