// Single-process occlusion-culling baselines that render while they cull, for the benchmark:
// the naive stop-and-wait hierarchical query, and coherent hierarchical culling
// (CHC, Bittner et al. 2004: previous-frame visibility, queries interleaved with rendering, no
// waiting for previously visible leaves).
//
// Both cull with a depth-only pass: the leaves they accept are drawn into the depth buffer as the
// traversal reaches them (front to back), so they occlude what follows. The frame itself is a
// second, shaded pass over the accepted leaves in item order (items_of_nodes, the one draw order
// everywhere) after a depth clear. Shading in traversal order instead made the frames differ
// from brute force wherever two coplanar surfaces tie in depth (the first drawn wins a tie under
// GL_GREATER): on the duplex walk, 5 pixels at 512x512 and 127 pixels in one frame at 400x300,
// although every visible leaf was drawn.
#pragma once
#include <cstdint>
#include <vector>

#include "common/camera.hpp"
#include "common/gl/box_query.hpp"
#include "common/gl/scene_renderer.hpp"
#include "common/scene/hierarchy.hpp"

namespace occ {

struct BaselineStats {
  uint64_t queries = 0;
  uint64_t nodes_drawn = 0;
  uint64_t triangles = 0;           // of the shaded pass
  std::vector<uint32_t> drawn;      // the accepted leaves (node ids), in traversal order
};

// Front-to-back traversal; every node in the frustum is queried and its result awaited before
// going on; visible leaves are drawn (depth only) at once so they occlude what follows; then the
// shaded pass. The caller has begun the frame (SceneRenderer::begin_frame).
BaselineStats render_stop_and_wait(const Hierarchy& h, const Camera& cam, SceneRenderer& r, BoxQuerier& q);

// CHC: keeps each node's visibility from the previous frame. Previously visible interior nodes
// are opened without a query; previously visible leaves are drawn at once and queried only to
// update their visibility; previously invisible nodes are queried and traversed when the result
// says visible. Results are read when ready (or when nothing else is left to do). Drawing is
// depth only until the shaded pass at the end, as for render_stop_and_wait.
class ChcRenderer {
 public:
  explicit ChcRenderer(const Hierarchy& h) : h_(h), visible_(h.size(), 0) {}
  BaselineStats render(const Camera& cam, SceneRenderer& r, BoxQuerier& q);

 private:
  const Hierarchy& h_;
  std::vector<uint8_t> visible_;  // per node, from the previous frame
};

}  // namespace occ
