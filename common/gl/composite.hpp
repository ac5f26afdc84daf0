// Sort-last compositing: another renderer's colour and depth of the same camera and viewport
// (SceneRenderer::Part::second, read back with read_rgba / read_depth) merged into the current
// framebuffer, pixel by pixel, where its depth is strictly nearer (reverse-Z: greater) than the
// depth there. A full-screen triangle writes the texel's colour and, as gl_FragDepth, its depth:
// the colour is RGBA8 in and out (exact), the depth a 32-bit float in and out (exact), and the
// depth test is the renderers' own GL_GREATER, so ties keep what is already there, the draw that
// came first in one pass. A pixel the other renderer left at the clear depth (0) never passes.
// Contracts: the GlContext is current on the calling thread and outlives the compositor; the
// images match its viewport (else std::invalid_argument).
#pragma once
#include <span>

#include "common/gl/context.hpp"
#include "common/image.hpp"

namespace occ {

class DepthCompositor {
 public:
  explicit DepthCompositor(GlContext& ctx);
  ~DepthCompositor();
  DepthCompositor(const DepthCompositor&) = delete;
  DepthCompositor& operator=(const DepthCompositor&) = delete;

  // colour: top row first (read_rgba); depth: row 0 at the bottom (read_depth).
  void composite(const Image& color, std::span<const float> depth);

 private:
  const GlApi& gl_;
  int width_, height_;
  GLuint program_ = 0, vao_ = 0, color_tex_ = 0, depth_tex_ = 0;
};

}  // namespace occ
