// The shader variants of SceneRenderer (scene_renderer.hpp describes the modes and materials).
// One GLSL source for every variant, specialised by #defines: a mode (Shaded, DepthOnly,
// ItemIds) and material variant bits. Internal to occ_gl: SceneGpu compiles the variants a scene
// uses, SceneRenderer binds them.
#pragma once
#include <cstdint>
#include <string>

#include "common/gl/gl_api.hpp"

namespace occ {

// How SceneRenderer draws (SceneRenderer::Mode).
enum class DrawMode { Shaded, DepthOnly, ItemIds };

namespace gl_detail {

// Material variant bits (a shader variant per combination the scene uses).
// kFlat: lit with each triangle's own normal (Mesh::flat).
constexpr unsigned kTextured = 1, kMask = 2, kBlend = 4, kUnlit = 8, kVertexColor = 16, kFlat = 32;
constexpr unsigned kVariants = 64;  // every combination of the bits
// Face culling of an object's triangles.
constexpr uint8_t kCullNone = 0, kCullBackCcw = 1, kCullBackCw = 2;

// The variant bits a mode actually uses: depth and id passes only need the alpha test (and its
// texture) of MASK materials; BLEND items never reach them.
unsigned mode_bits(DrawMode mode, unsigned bits);
// Leaf LOD draws: no texture coordinates, no vertex colours.
inline unsigned lod_bits(unsigned bits) { return bits & ~(kTextured | kVertexColor); }
// E.g. "textured+masked"; "plain" for 0.
std::string variant_name(unsigned bits);
// Compiles and links the program of `mode` and `bits` (its one uniform: mat4 u_projection).
// Throws std::runtime_error as link_program does.
GLuint link_scene_program(const GlApi& gl, DrawMode mode, unsigned bits);

}  // namespace gl_detail
}  // namespace occ
