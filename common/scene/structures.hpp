// Generated structures of the kinds where culling beyond the frustum is hard to make pay
// (--scene bridge|office|pipes, scene_io.hpp): thousands of objects hidden inside others, a
// building the walk goes through wall by wall, a model where most of what is in view shows.
// Deterministic; Y up, metres. The benchmarks of the cluster against the limit (a render of
// exactly the visible set, scripts/oracle_table.sh) run on these.
#pragma once
#include "common/scene/scene.hpp"

namespace occ {

// bridge[:N]: N (1..200, default 16) spans of 30 m along a horizontal arc of radius 120 m (the
// deck turns 14.3 degrees a span and rises 1 in 50 along it), on a ground 20 m beyond its plan, each a separate set of concrete members
// (a deck slab 12 m wide and 0.3 m thick at y 8, two box girders under it, a pier with its cap at
// the span's start, two parapets) and, inside the concrete with 5 cm of cover, its reinforcement as
// separate objects: octagonal bars along and across the deck, along the girders with a stirrup
// every 0.3 m, and up the pier with ties. About 600 objects a span, most of them bars, which
// never show: only the concrete is visible. The bars follow the arc, so their world boxes are
// diagonal and poke out of the concrete that hides them.
Scene bridge(int spans);

// office[:N]: an office building of N (1..100, default 16) bays of 6 m along x, 18 m deep (z -9..9),
// three storeys of 3.5 m; each bay a room on each side of a corridor (z -1.2..1.2) on every storey,
// separated by cross walls of 0.2 m with a door (1 m wide, off the corridor's axis); every third
// cross wall a glass partition (BLEND, occludes nothing); in every room desks, chairs, cabinets
// and screens (about 30 objects). walk:N goes straight along x at eye height through the cross
// walls, the corridor's walls with glazed doors on either side: the eye passes through a wall
// every 6 m.
Scene office(int bays);

// pipes[:N]: N (1..100, default 24) modules of 6 m, in racks of 8 along x, racks 14 m apart in z: a steel frame per module
// (columns and beams), three levels of pipes along x (8 per level, 0.1-0.4 m diameter, 24
// sides), branches dropping from them every few metres with elbows, flanges and valves, and cable
// trays: about 250 open objects a module, most of them visible from outside (an orbit).
Scene pipes(int modules);

}  // namespace occ
