// The visibility hold: hysteresis for a switch node's visible set (HcChoices::visibility_hold;
// SwitchStep::hc applies it).
#pragma once
#include <cstdint>
#include <span>
#include <vector>

#include "common/camera.hpp"
#include "common/lod/lod_select.hpp"
#include "common/scene/hierarchy.hpp"

namespace occ {

// Hysteresis for the visible set: a node HC found visible (in two frames, see recent())
// stays in V for up to `frames` frames after the last frame it was seen, while it stays in the
// frustum. Leaves that
// flicker in and out of V between frames (a query that passes in one node's depth buffer and not
// in the other's, a leaf seen through a gap every other frame) then cost no ids on the wire and
// no re-draws at the edges of their visibility. Keeping more than is visible is conservative:
// frames never change. Node-local state: each switch node records what its own HC found and the
// additions it receives from the other node (an added id was found visible); what it cannot
// know (the other node's kept ids) only shortens the hold.
class VisibilityHold {
 public:
  VisibilityHold(size_t nodes, uint32_t frames) : frames_(frames), last_(nodes, 0), prev_(nodes, 0) {}
  uint32_t frames() const { return frames_; }
  // `node` was found visible in `frame`.
  void seen(uint32_t node, uint32_t frame) {
    if (frame + 1 <= last_.at(node)) return;
    prev_[node] = last_[node];
    last_[node] = frame + 1;
  }
  // Seen in one of the `frames` frames before `frame` (or in it), and once more before that within
  // 4 x `frames` frames. A node seen in one frame only is not held: a set that exploded for one
  // frame (start-up, the eye leaving a closed room) is not carried into the next frames.
  bool recent(uint32_t node, uint32_t frame) const {
    const uint32_t l = last_.at(node), p = prev_[node];
    return l != 0 && l - 1 + frames_ >= frame && p != 0 && p - 1 + 4 * frames_ >= frame;
  }
  // The renderables of `prev` (V_{f-1}, front-tracking coarsened) to keep in V_f beside `found`
  // (HC's result, ascending): recently seen, box not outside the frustum, and neither the same
  // node as, an ancestor of, nor a descendant of a node in `found` (V_f stays an antichain: one
  // representation per part of the scene). Ascending.
  std::vector<uint32_t> held(const Renderables& r, const Camera& cam, std::span<const uint32_t> prev,
                             std::span<const uint32_t> found, uint32_t frame) const;

 private:
  uint32_t frames_;
  std::vector<uint32_t> last_, prev_;  // per node: last / previous frame seen + 1 (0: never)
};

}  // namespace occ
