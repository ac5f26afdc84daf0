#include "common/gl/composite.hpp"

#include <stdexcept>
#include <string>

#include "common/gl/shader.hpp"

namespace occ {
namespace {

const char* const kVertex = R"(#version 450 core
void main() {  // one triangle over the whole viewport
  vec2 p = vec2(gl_VertexID == 1 ? 3.0 : -1.0, gl_VertexID == 2 ? 3.0 : -1.0);
  gl_Position = vec4(p, 0.0, 1.0);
}
)";

const char* const kFragment = R"(#version 450 core
layout(binding = 0) uniform sampler2D u_color;  // top row first
layout(binding = 1) uniform sampler2D u_depth;  // row 0 at the bottom
out vec4 out_color;
void main() {
  ivec2 p = ivec2(gl_FragCoord.xy);
  ivec2 size = textureSize(u_color, 0);
  out_color = texelFetch(u_color, ivec2(p.x, size.y - 1 - p.y), 0);
  gl_FragDepth = texelFetch(u_depth, p, 0).r;
}
)";

}  // namespace

DepthCompositor::DepthCompositor(GlContext& ctx) : gl_(ctx.gl()), width_(ctx.width()), height_(ctx.height()) {
  program_ = link_program(gl_, kVertex, kFragment);
  gl_.CreateVertexArrays(1, &vao_);
  gl_.CreateTextures(GL_TEXTURE_2D, 1, &color_tex_);
  gl_.TextureStorage2D(color_tex_, 1, GL_RGBA8, width_, height_);
  gl_.CreateTextures(GL_TEXTURE_2D, 1, &depth_tex_);
  gl_.TextureStorage2D(depth_tex_, 1, GL_R32F, width_, height_);
  for (GLuint t : {color_tex_, depth_tex_}) {
    gl_.TextureParameteri(t, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    gl_.TextureParameteri(t, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
  }
}

DepthCompositor::~DepthCompositor() {
  gl_.DeleteTextures(1, &color_tex_);
  gl_.DeleteTextures(1, &depth_tex_);
  gl_.DeleteVertexArrays(1, &vao_);
  gl_.DeleteProgram(program_);
}

void DepthCompositor::composite(const Image& color, std::span<const float> depth) {
  const size_t px = size_t(width_) * size_t(height_);
  if (color.width != width_ || color.height != height_ || color.rgba.size() != 4 * px || depth.size() != px)
    throw std::invalid_argument("DepthCompositor: a " + std::to_string(color.width) + "x" + std::to_string(color.height) +
                                " image with " + std::to_string(depth.size()) + " depth values for a " +
                                std::to_string(width_) + "x" + std::to_string(height_) + " viewport");
  gl_.PixelStorei(GL_UNPACK_ALIGNMENT, 1);
  gl_.TextureSubImage2D(color_tex_, 0, 0, 0, width_, height_, GL_RGBA, GL_UNSIGNED_BYTE, color.rgba.data());
  gl_.TextureSubImage2D(depth_tex_, 0, 0, 0, width_, height_, GL_RED, GL_FLOAT, depth.data());
  gl_.UseProgram(program_);
  gl_.BindVertexArray(vao_);
  gl_.BindTextureUnit(0, color_tex_);
  gl_.BindTextureUnit(1, depth_tex_);
  gl_.ColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
  gl_.DepthMask(GL_TRUE);
  gl_.Enable(GL_DEPTH_TEST);
  gl_.DepthFunc(GL_GREATER);
  gl_.Disable(GL_CULL_FACE);
  gl_.Disable(GL_BLEND);
  gl_.DrawArrays(GL_TRIANGLES, 0, 3);
}

}  // namespace occ
