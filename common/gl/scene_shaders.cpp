#include "common/gl/scene_shaders.hpp"

#include "common/gl/shader.hpp"

namespace occ::gl_detail {
namespace {

// One source for every variant, specialised by #defines. The per-draw data are instanced
// attributes (divisor 1): on llvmpipe they cost less CPU per frame than an SSBO of per-object
// records indexed per vertex (measured). Lighting is per fragment. Per vertex (Gouraud, like
// fixed-function GL) costs llvmpipe less, but Gouraud shading depends on the tessellation: a LOD
// no longer looks like the full detail it stands for (many more of a frame's pixels differ
// visibly from the full detail than with per-fragment lighting).
const char* const kVertexBody = R"(
layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;
layout(location = 2) in mat4 in_model_view;       // per draw (locations 2..5)
layout(location = 6) in vec4 in_normal_color[3];  // per draw: normal matrix columns, colour in w
layout(location = 9) in uint in_id;               // per draw: id + 1
layout(location = 10) in vec4 in_vertex_color;    // per vertex: COLOR_0 or HLOD colour (else white)
layout(location = 11) in vec2 in_alpha_cutoff;    // per draw: base colour alpha, MASK cutoff
#ifdef TEXTURED
layout(location = 12) in vec2 in_uv;              // per vertex
invariant out vec2 v_uv;
#endif
uniform mat4 u_projection;
// Section planes in view space (common/section.hpp): kept where dot(xyz, p) + w >= 0; the
// renderer enables GL_CLIP_DISTANCE0.. for the planes in use.
uniform vec4 u_sections[6];
out float gl_ClipDistance[6];
invariant gl_Position;
#if (defined(SHADED) || defined(MASK)) && defined(VERTEX_COLOR)
invariant out vec4 v_color;  // rgb: base colour (Shaded), a: alpha
#elif defined(SHADED) || defined(MASK)
flat out vec4 v_color;       // the object's colour: nothing to interpolate
#endif
#ifdef MASK
flat out float v_cutoff;
#endif
#ifdef IDS
flat out uint v_id;
#endif
#if defined(LIT) && defined(FLAT)
out vec3 v_view;  // view-space position: its derivatives span the triangle's plane
#elif defined(LIT)
out vec3 v_normal;
#endif
void main() {
  vec4 p = in_model_view * vec4(in_position, 1.0);
  gl_Position = u_projection * p;
  for (int i = 0; i < 6; ++i) gl_ClipDistance[i] = dot(u_sections[i].xyz, p.xyz) + u_sections[i].w;
#if defined(SHADED) || defined(MASK)
  float alpha = in_alpha_cutoff.x * in_vertex_color.a;
#endif
#ifdef SHADED
  vec3 base = vec3(in_normal_color[0].w, in_normal_color[1].w, in_normal_color[2].w) * in_vertex_color.rgb;
  v_color = vec4(base, alpha);
#if defined(LIT) && defined(FLAT)
  v_view = p.xyz;
#elif defined(LIT)
  v_normal = mat3(in_normal_color[0].xyz, in_normal_color[1].xyz, in_normal_color[2].xyz) * in_normal;
#endif
#elif defined(MASK)
  v_color = vec4(0.0, 0.0, 0.0, alpha);
#endif
#ifdef MASK
  v_cutoff = in_alpha_cutoff.y;
#endif
#ifdef IDS
  v_id = in_id;
#endif
#ifdef TEXTURED
  v_uv = in_uv;
#endif
}
)";

const char* const kFragmentBody = R"(
#ifdef TEXTURED
layout(binding = 0) uniform sampler2D u_base_color;
in vec2 v_uv;
#endif
#if (defined(SHADED) || defined(MASK)) && defined(VERTEX_COLOR)
in vec4 v_color;
#elif defined(SHADED) || defined(MASK)
flat in vec4 v_color;
#endif
#ifdef MASK
flat in float v_cutoff;
#endif
#ifdef IDS
flat in uint v_id;
#endif
#if defined(SHADED) || defined(IDS)
out vec4 out_color;
#endif
#if defined(LIT) && defined(FLAT)
in vec3 v_view;
#elif defined(LIT)
in vec3 v_normal;
#endif
void main() {
#if defined(SHADED) || defined(MASK)
  vec4 c = v_color;
#ifdef LIT
  // Headlight: directional, along the view axis (view-space z), two-sided. One interpolant (the
  // normal) instead of two: a light at the eye also needed the view-space position, and
  // llvmpipe sets up every interpolant per triangle (one fewer measured faster with
  // the reference renderer).
  // Flat: the triangle's own normal, from the screen derivatives of its view-space position
  // (a 2x2 quad's fragments all belong to one triangle, so they span its plane).
#ifdef FLAT
  vec3 v_normal = cross(dFdx(v_view), dFdy(v_view));
#endif
  float lambert = min(abs(v_normal.z) * inversesqrt(max(dot(v_normal, v_normal), 1e-36)), 1.0);
  c.rgb *= 0.2 + 0.8 * lambert;
#endif
#ifdef TEXTURED
  c *= texture(u_base_color, v_uv);
#endif
#ifdef MASK
  if (c.a < v_cutoff) discard;
#endif
#endif
#ifdef SHADED
#ifdef BLEND
  out_color = c;
#else
  out_color = vec4(c.rgb, 1.0);
#endif
#elif defined(IDS)
  out_color = vec4((uvec4(v_id) >> uvec4(0, 8, 16, 24)) & 0xffu) / 255.0;
#endif
}
)";

std::string defines(DrawMode mode, unsigned bits) {
  std::string d = "#version 450 core\n";
  d += mode == DrawMode::Shaded ? "#define SHADED\n" : mode == DrawMode::ItemIds ? "#define IDS\n" : "#define DEPTH\n";
  if (bits & kTextured) d += "#define TEXTURED\n";
  if (bits & kMask) d += "#define MASK\n";
  if (bits & kBlend) d += "#define BLEND\n";
  if (bits & kUnlit) d += "#define UNLIT\n";
  if (bits & kVertexColor) d += "#define VERTEX_COLOR\n";
  if (mode == DrawMode::Shaded && !(bits & kUnlit)) d += "#define LIT\n";
  if (bits & kFlat) d += "#define FLAT\n";  // only lit variants carry it (look_of)
  return d;
}

}  // namespace

unsigned mode_bits(DrawMode mode, unsigned bits) {
  if (mode == DrawMode::Shaded) return bits;
  return (bits & kMask) ? (bits & (kMask | kTextured | kVertexColor)) : 0;
}

std::string variant_name(unsigned bits) {
  std::string n;
  auto add = [&](const char* s) { n += n.empty() ? s : std::string("+") + s; };
  if (bits & kTextured) add("textured");
  if (bits & kMask) add("masked");
  if (bits & kBlend) add("blended");
  if (bits & kUnlit) add("unlit");
  if (bits & kVertexColor) add("vertex-coloured");
  if (bits & kFlat) add("flat");
  return n.empty() ? "plain" : n;
}

GLuint link_scene_program(const GlApi& gl, DrawMode mode, unsigned bits) {
  const std::string head = defines(mode, bits);
  return link_program(gl, head + kVertexBody, head + kFragmentBody);
}

}  // namespace occ::gl_detail
