// render_client --window's culling overlay (the O key): boxes tinted over a finished frame, with
// no depth test, so boxes hidden behind what the frame shows tint the pixels in front of them.
// The tint is cull_overview's colour for occlusion-culled nodes (orange, 255,110,0) at opacity
// 0.3 per box face layer (front faces only, so each box tints its silhouette once).
// Contracts: the GlContext is current on the calling thread for every call and outlives the
// overlay.
#pragma once
#include <span>

#include "common/camera.hpp"
#include "common/gl/context.hpp"

namespace occ {

class BoxOverlay {
 public:
  // Links the overlay's program (box_query.hpp's box vertex shader, one flat tint).
  explicit BoxOverlay(GlContext& ctx);
  ~BoxOverlay();
  BoxOverlay(const BoxOverlay&) = delete;
  BoxOverlay& operator=(const BoxOverlay&) = delete;

  // Tints each non-empty box of `boxes` (world space) as `cam` sees it, over the frame in the
  // framebuffer: goes after the frame. Leaves blending and face culling off, depth test and
  // depth writes on.
  void draw(const Camera& cam, std::span<const Aabb> boxes);

 private:
  const GlApi& gl_;
  GLuint program_ = 0, vao_ = 0;
  GLint view_projection_loc_ = -1, min_loc_ = -1, max_loc_ = -1;
};

}  // namespace occ
