// The occlusion switch's per-frame logic, pure (no GL, no sockets): what every process does with
// V_{f-1} and camera f, and what the HC node does to find V_f. The switch nodes, the render
// client, cull_overview and the tests all call this one module, so the three processes agree by
// construction; the processes keep only their I/O and GL.
//
// Frame f on each process (front.hpp explains the fronts):
//   every process, on receiving camera f:  coarsen(V_{f-1}, camera f) -> V', hash(V')
//   HC node:  hc(V', camera f, queries) streams V_f − V' and V' − V_f (DiffSender) and returns
//             EndOfFrame(f) with front_hash = hash(V'), the set hash of V_f and its statistics
//   receivers (OR node, render client): apply the diff to V', check both hashes.
#pragma once
#include <cstdint>
#include <vector>

#include "common/cull/culling.hpp"
#include "common/cull/visibility_hold.hpp"
#include "common/scene/hierarchy.hpp"
#include "common/lod/lod.hpp"
#include "protocol/cluster/cluster.hpp"
#include "protocol/visible_set.hpp"

namespace occ {

struct HcFrame {
  wire::EndOfFrame eof;  // set fields, front_hash, queries and triangles; the caller adds times
  CullStats stats;
  uint32_t tests_above_fronts = 0;  // interior nodes a root traversal would have queried
  uint32_t held = 0;                // renderables kept in V_f by the hold, not found this frame
};

class SwitchStep {
 public:
  // `tracking`: front tracking on this process (config.front_tracking, and a switch, not a
  // single server).
  SwitchStep(const Renderables& r, const LodPolicy& lod, bool tracking);
  SwitchStep(const Renderables& r, const ClusterConfig& c, int viewport_height_px)
      : SwitchStep(r, c.lod_policy(viewport_height_px), c.front_tracking) {}

  bool tracking() const { return tracking_; }

  // Front tracking step 1 (front.hpp), on every process for camera f before frame f's diff:
  // V_{f-1} becomes V' in place. Returns front_hash(V'), 0 when not tracking (V unchanged).
  uint64_t coarsen(VisibleSet& visible, const Camera& cam) const;

  // HC(f) on V_{f-1}: coarsens it (above), starts from its fronts (or the root), queries, streams
  // the diff through `out` and leaves V_f in `visible`. Returns EndOfFrame(f), not yet sent.
  // `o`: the node's choices with their state (o.choices, o.skipper, o.occluders: how V_f is
  // found, never what it must contain); hc() sets its start, on_visible, stats and
  // visible_pixel_lod. `hold` (VisibilityHold, o.choices.visibility_hold): hc() records what it
  // found and keeps recently seen renderables of V_{f-1} in V_f; the caller records the other
  // node's additions.
  HcFrame hc(uint32_t frame, VisibleSet& visible, const Camera& cam, OcclusionQueries& q, HcOptions o,
             DiffSender& out, VisibilityHold* hold = nullptr) const;

 private:
  const Renderables& r_;
  LodPolicy lod_;
  bool tracking_;
};

}  // namespace occ
