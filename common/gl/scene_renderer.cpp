#include "common/gl/scene_renderer.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <mutex>
#include <stdexcept>
#include <string>
#include <tuple>

#include <errno.h>
#include <malloc.h>
#include <glm/gtc/type_ptr.hpp>

#include "common/gl/shader.hpp"
#include "common/hash.hpp"

namespace occ {
namespace {

// Material variant bits (a shader variant per combination the scene uses).
constexpr unsigned kTextured = 1, kMask = 2, kBlend = 4, kUnlit = 8, kVertexColor = 16;
constexpr unsigned kVariants = 32;  // = the second extent of SceneRenderer::programs_
// Face culling of an object's triangles.
constexpr uint8_t kCullNone = 0, kCullBackCcw = 1, kCullBackCw = 2;
constexpr uint64_t kBlendKey = uint64_t(1) << 63;

// The variant bits a mode actually uses: depth and id passes only need the alpha test (and its
// texture) of MASK materials; BLEND items never reach them.
unsigned mode_bits(SceneRenderer::Mode mode, unsigned bits) {
  if (mode == SceneRenderer::Mode::Shaded) return bits;
  return (bits & kMask) ? (bits & (kMask | kTextured | kVertexColor)) : 0;
}

// One source for every variant, specialised by #defines. The per-draw data are instanced
// attributes (divisor 1): on llvmpipe this took 10-15% less CPU per frame than an SSBO of
// per-object records indexed per vertex (measured, 27k draws, 8M triangles). Lighting is per
// fragment. Per vertex (Gouraud, like fixed-function GL) took 15-20 % less CPU per frame on the
// duplex at 1024^2 and the saw at 512^2 (llvmpipe), but Gouraud shading depends on the
// tessellation: a LOD no longer looks like the full detail it stands for (the city at tau 3 px:
// up to 17 % of a frame's pixels off by more than 16 levels, against < 5 % per fragment).
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
#ifdef LIT
out vec3 v_normal;
#endif
void main() {
  vec4 p = in_model_view * vec4(in_position, 1.0);
  gl_Position = u_projection * p;
#if defined(SHADED) || defined(MASK)
  float alpha = in_alpha_cutoff.x * in_vertex_color.a;
#endif
#ifdef SHADED
  vec3 base = vec3(in_normal_color[0].w, in_normal_color[1].w, in_normal_color[2].w) * in_vertex_color.rgb;
  v_color = vec4(base, alpha);
#ifdef LIT
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
#ifdef LIT
in vec3 v_normal;
#endif
void main() {
#if defined(SHADED) || defined(MASK)
  vec4 c = v_color;
#ifdef LIT
  // Headlight: directional, along the view axis (view-space z), two-sided. One interpolant (the
  // normal) instead of two: a light at the eye also needed the view-space position, and
  // llvmpipe sets up every interpolant per triangle (saw 512^2 render ~10 % and duplex 1024^2
  // ~5 % less time per frame, /tmp A/B of render_client --reference).
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

std::string defines(SceneRenderer::Mode mode, unsigned bits) {
  std::string d = "#version 450 core\n";
  d += mode == SceneRenderer::Mode::Shaded ? "#define SHADED\n" : mode == SceneRenderer::Mode::ItemIds ? "#define IDS\n" : "#define DEPTH\n";
  if (bits & kTextured) d += "#define TEXTURED\n";
  if (bits & kMask) d += "#define MASK\n";
  if (bits & kBlend) d += "#define BLEND\n";
  if (bits & kUnlit) d += "#define UNLIT\n";
  if (bits & kVertexColor) d += "#define VERTEX_COLOR\n";
  if (mode == SceneRenderer::Mode::Shaded && !(bits & kUnlit)) d += "#define LIT\n";
  return d;
}

// Leaf LOD draws: no texture coordinates, no vertex colours.
unsigned lod_bits(unsigned bits) { return bits & ~(kTextured | kVertexColor); }

std::string variant_name(unsigned bits) {
  std::string n;
  auto add = [&](const char* s) { n += n.empty() ? s : std::string("+") + s; };
  if (bits & kTextured) add("textured");
  if (bits & kMask) add("masked");
  if (bits & kBlend) add("blended");
  if (bits & kUnlit) add("unlit");
  if (bits & kVertexColor) add("vertex-coloured");
  return n.empty() ? "plain" : n;
}

glm::vec4 object_color(uint32_t object) {
  const uint64_t h = mix64(object + 1);
  auto channel = [&](int k) { return 0.45f + 0.5f * float((h >> (8 * k)) & 0xff) / 255.0f; };
  return {channel(0), channel(1), channel(2), 1.0f};
}

uint32_t pack_rgba8(glm::vec4 c) {
  uint32_t rgba = 0;
  for (int k = 0; k < 4; ++k) rgba |= uint32_t(std::lround(std::clamp(c[k], 0.0f, 1.0f) * 255.0f)) << (8 * k);
  return rgba;
}

// OCC_FLUSH_TRIANGLES fixes SceneRenderer's part size (see set_flush_triangles); nullopt if unset.
std::optional<uint32_t> flush_triangles_from_environment() {
  const char* v = std::getenv("OCC_FLUSH_TRIANGLES");
  if (!v || !*v) return std::nullopt;
  char* end = nullptr;
  errno = 0;
  const unsigned long long n = std::strtoull(v, &end, 10);
  if (*v < '0' || *v > '9' || *end || errno || n > 0xffffffffull)
    throw std::runtime_error(std::string("OCC_FLUSH_TRIANGLES=") + v +
                             ": not a triangle count (a whole number, 0 turns the flushes off)");
  return uint32_t(n);
}

}  // namespace

// Without Upload::release nothing is written through these pointers.
SceneRenderer::SceneRenderer(GlContext& ctx, const Scene& scene, const Hierarchy& hierarchy, const LodData* lod)
    : SceneRenderer(ctx, const_cast<Scene&>(scene), hierarchy, const_cast<LodData*>(lod), Upload{}) {}

SceneRenderer::SceneRenderer(GlContext& ctx, Scene& scene, const Hierarchy& hierarchy, LodData* release_lod,
                             const Upload& upload)
    : gl_(ctx.gl()), hierarchy_(hierarchy) {
  if (const std::optional<uint32_t> n = flush_triangles_from_environment()) {
    flush_triangles_ = *n;
    flush_from_environment_ = true;
  }
  const LodData* lod = release_lod;
  if (scene.geometry_released())
    throw std::logic_error("SceneRenderer: the geometry of " + scene.source + " was released after an upload");
  struct Vertex {
    glm::vec3 position, normal;
    uint32_t color;  // RGBA8
  };
  static_assert(sizeof(Vertex) == 28 && sizeof(DrawRecord) == 124 && sizeof(IndirectCommand) == 20);

  // What each object draws with.
  transforms_.reserve(scene.objects.size());
  looks_.reserve(scene.objects.size());
  std::vector<uint8_t> used_texture(scene.textures.size(), 0);
  std::vector<uint8_t> mesh_textured(scene.meshes.size(), 0);
  for (uint32_t o = 0; o < scene.objects.size(); ++o) {
    const Object& obj = scene.objects[o];
    transforms_.push_back(obj.transform);
    const Mesh& mesh = scene.meshes[obj.mesh];
    if (mesh.material != kNoMaterial && mesh.material >= scene.materials.size())
      throw std::runtime_error("SceneRenderer: mesh " + std::to_string(obj.mesh) + " has material " +
                               std::to_string(mesh.material) + " of " + std::to_string(scene.materials.size()));
    const Material* mat = scene.material_of(obj.mesh);
    ObjectLook look;
    if (!mesh.colors.empty() && mesh.colors.size() == mesh.positions.size()) look.bits |= kVertexColor;
    const bool mirrored = glm::determinant(glm::dmat3(obj.transform)) < 0.0;
    if (!mat) {
      look.color = object_color(o);
      look.cull = kCullNone;
    } else {
      look.color = mat->object_color ? glm::vec4(glm::vec3(object_color(o)), mat->base_color.a) : mat->base_color;
      look.cutoff = mat->alpha_cutoff;
      look.cull = mat->double_sided ? kCullNone : mirrored ? kCullBackCw : kCullBackCcw;
      if (mat->alpha_mode == AlphaMode::Mask) look.bits |= kMask;
      if (mat->alpha_mode == AlphaMode::Blend) look.bits |= kBlend;
      if (mat->unlit) look.bits |= kUnlit;
      if (mat->base_color_texture >= 0 && mesh.uvs.size() == mesh.positions.size()) {
        if (size_t(mat->base_color_texture) >= scene.textures.size() ||
            scene.textures[size_t(mat->base_color_texture)].image >= scene.images.size())
          throw std::runtime_error("SceneRenderer: material '" + mat->name + "' has texture " +
                                   std::to_string(mat->base_color_texture) + " without an image");
        look.bits |= kTextured;
        look.texture = mat->base_color_texture;
      }
    }
    looks_.push_back(look);
  }
  // Objects that draw something (have items): their variants, textures, boxes.
  std::vector<Aabb> object_box(scene.objects.size());
  std::vector<uint8_t> drawn(scene.objects.size(), 0);
  for (const Item& it : hierarchy.items()) {
    object_box[it.object].grow(it.box);
    drawn[it.object] = 1;
  }
  bool any_textured = false;
  for (uint32_t o = 0; o < scene.objects.size(); ++o)
    if (drawn[o] && (looks_[o].bits & kTextured)) {
      used_texture[size_t(looks_[o].texture)] = 1;
      mesh_textured[scene.objects[o].mesh] = 1;
      any_textured = true;
    }

  // Geometry goes to GL in segments (Upload): a segment is staged on the CPU until it holds about
  // segment_bytes, then becomes its own vertex/index/uv buffers. With Upload::release each mesh's
  // CPU arrays are freed as soon as they are staged, so the CPU geometry shrinks as the driver's
  // copy grows (plant:40: 6.5 GB a process with one buffer and kept arrays, see docs/scale.md).
  std::vector<const LodMesh*> lod_meshes;  // upload order: cluster LODs, then HLODs by node id
  std::vector<uint32_t> lod_node;          // per entry of lod_meshes: its node (HLODs) or kNoNode
  if (lod) {
    for (const LodMesh& m : lod->cluster_lods()) {
      lod_meshes.push_back(&m);
      lod_node.push_back(kNoNode);
    }
    for (uint32_t id = 0; id < hierarchy.size(); ++id)
      if (const LodMesh* m = lod->hlod(id)) {
        lod_meshes.push_back(m);
        lod_node.push_back(id);
      }
    for (const LodMesh* m : lod_meshes)
      if (m->released) throw std::logic_error("SceneRenderer: the LOD data's geometry was released");
  }
  const size_t limit = std::max<size_t>(upload.segment_bytes, 4096);
  std::vector<Vertex> vstage;
  std::vector<uint32_t> istage;
  std::vector<glm::vec2> uvstage;
  auto flush_segment = [&] {
    Segment sg;
    auto create = [&](GLuint* buf, const void* data, size_t bytes) {
      gl_.CreateBuffers(1, buf);
      gl_.NamedBufferStorage(*buf, GLsizeiptr(std::max<size_t>(1, bytes)), bytes ? data : nullptr, 0);
    };
    create(&sg.vertices, vstage.data(), vstage.size() * sizeof(Vertex));
    create(&sg.indices, istage.data(), istage.size() * sizeof(uint32_t));
    if (any_textured) create(&sg.uvs, uvstage.data(), uvstage.size() * sizeof(glm::vec2));
    segments_.push_back(sg);
    vstage.clear();
    istage.clear();
    uvstage.clear();
  };
  // Starts a new segment unless nv vertices and ni indices still fit the current one.
  auto make_room = [&](size_t nv, size_t ni) {
    if ((!vstage.empty() || !istage.empty()) &&
        (vstage.size() + nv) * sizeof(Vertex) + (istage.size() + ni) * sizeof(uint32_t) > limit)
      flush_segment();
    if (vstage.size() + nv > size_t(INT32_MAX)) throw std::runtime_error("SceneRenderer: more than 2^31 vertices in a mesh");
  };
  uint64_t freed_since_trim = 0;
  auto released = [&](uint64_t bytes) {  // give freed heap pages back to the system now and then
    freed_since_trim += bytes;
    if (freed_since_trim >= (uint64_t(64) << 20)) {
      ::malloc_trim(0);
      freed_since_trim = 0;
    }
  };

  std::vector<int32_t> base_vertex(scene.meshes.size());
  std::vector<uint32_t> first_index(scene.meshes.size()), mesh_segment(scene.meshes.size());
  for (size_t m = 0; m < scene.meshes.size(); ++m) {
    Mesh& mesh = scene.meshes[m];
    make_room(mesh.positions.size(), mesh.indices.size());
    base_vertex[m] = int32_t(vstage.size());
    first_index[m] = uint32_t(istage.size());
    mesh_segment[m] = uint32_t(segments_.size());
    const bool colored = mesh.colors.size() == mesh.positions.size();
    for (size_t v = 0; v < mesh.positions.size(); ++v)
      vstage.push_back({mesh.positions[v], v < mesh.normals.size() ? mesh.normals[v] : glm::vec3(0, 0, 1),
                        colored ? mesh.colors[v] : 0xffffffffu});
    if (any_textured) {
      const bool with_uv = mesh_textured[m] && mesh.uvs.size() == mesh.positions.size();
      for (size_t v = 0; v < mesh.positions.size(); ++v) uvstage.push_back(with_uv ? mesh.uvs[v] : glm::vec2(0.0f));
    }
    istage.insert(istage.end(), mesh.indices.begin(), mesh.indices.end());
    if (upload.release) {
      const uint64_t bytes = mesh.positions.capacity() * 24 + mesh.indices.capacity() * 4 +
                             mesh.uvs.capacity() * 8 + mesh.colors.capacity() * 4;
      mesh.release_geometry();
      released(bytes);
    }
  }
  if (lod) {
    hlod_of_node_.assign(hierarchy.size(), kNoNode);
    for (size_t k = 0; k < lod_meshes.size(); ++k) {
      const LodMesh& m = *lod_meshes[k];
      make_room(m.positions.size(), m.indices.size());
      ItemDraw d{uint32_t(m.indices.size()), uint32_t(istage.size()), int32_t(vstage.size()), 0,
                 uint32_t(segments_.size())};
      for (size_t v = 0; v < m.positions.size(); ++v) {
        uint32_t rgba = 0xffffffffu;  // leaf LODs: the object's colour
        if (!m.objects.empty()) {     // HLODs: each vertex its source object's colour
          const uint32_t o = m.objects[v];
          rgba = pack_rgba8(o < looks_.size() ? glm::vec4(glm::vec3(looks_[o].color), 1.0f) : object_color(o));
        }
        vstage.push_back({m.positions[v], m.normals[v], rgba});
        if (any_textured) uvstage.push_back(glm::vec2(0.0f));
      }
      istage.insert(istage.end(), m.indices.begin(), m.indices.end());
      if (lod_node[k] == kNoNode) {
        lod_draws_.push_back(d);
      } else {
        const uint32_t id = lod_node[k];
        hlod_of_node_[id] = uint32_t(hlod_draws_.size());
        d.object = uint32_t(transforms_.size());  // pseudo-object: translation to the origin
        glm::dmat4 t(1.0);
        t[3] = glm::dvec4(m.origin, 1.0);
        transforms_.push_back(t);
        ObjectLook hlod_look;  // opaque, lit, double-sided, white x vertex colours
        hlod_look.bits = kVertexColor;
        looks_.push_back(hlod_look);
        object_box.push_back(hierarchy.node(id).box);
        hlod_draws_.push_back(d);
      }
      if (upload.release) {
        const uint64_t bytes = m.positions.capacity() * 24 + m.objects.capacity() * 4 + m.indices.capacity() * 4;
        release_lod->release(m);
        released(bytes);
      }
    }
    item_slot_ = lod->item_slots();
  }
  if (!vstage.empty() || !istage.empty() || segments_.empty()) flush_segment();
  std::vector<Vertex>().swap(vstage);
  std::vector<uint32_t>().swap(istage);
  std::vector<glm::vec2>().swap(uvstage);
  if (upload.release) ::malloc_trim(0);
  item_draws_.reserve(hierarchy.items().size());
  for (const Item& it : hierarchy.items()) {
    const uint32_t mesh = scene.objects[it.object].mesh;
    const MeshCluster& cl = scene.meshes[mesh].clusters[it.cluster];
    item_draws_.push_back(
        {cl.index_count, first_index[mesh] + cl.first_index, base_vertex[mesh], it.object, mesh_segment[mesh]});
  }
  object_frame_.assign(transforms_.size(), 0);
  object_matrices_.resize(transforms_.size());
  normal_world_.reserve(transforms_.size());
  for (const glm::dmat4& t : transforms_) normal_world_.push_back(glm::transpose(glm::inverse(glm::dmat3(t))));
  centers_.reserve(object_box.size());
  for (const Aabb& b : object_box) centers_.push_back(b.empty() ? glm::dvec3(0.0) : b.center());

  // The variants the scene uses: full detail with its materials; LODs untextured; HLODs plain.
  std::vector<uint8_t> used[3];
  for (auto& u : used) u.assign(kVariants, 0);
  auto use = [&](unsigned bits) {
    used[0][bits] = 1;
    if (!(bits & kBlend)) {
      used[1][mode_bits(Mode::DepthOnly, bits)] = 1;
      used[2][mode_bits(Mode::ItemIds, bits)] = 1;
    }
  };
  for (uint32_t o = 0; o < scene.objects.size(); ++o)
    if (drawn[o]) {
      use(looks_[o].bits);
      if (!lod_draws_.empty()) use(lod_bits(looks_[o].bits));
      has_blended_ |= (looks_[o].bits & kBlend) != 0;
    }
  if (!hlod_draws_.empty()) use(kVertexColor);
  if (hierarchy.items().empty()) use(0);
  static const char* const kModeName[3] = {"shaded", "depth", "ids"};
  for (int m = 0; m < 3; ++m) {
    variants_ += std::string(m ? "; " : "") + kModeName[m] + ":";
    bool first = true;
    for (unsigned bits = 0; bits < kVariants; ++bits)
      if (used[m][bits]) {
        compile(Mode(m), bits);
        variants_ += std::string(first ? " " : ", ") + variant_name(bits);
        first = false;
      }
  }
  static std::once_flag logged;
  std::call_once(logged, [&] {
    size_t counts[3] = {}, textured = 0, single = 0;
    for (const Material& mat : scene.materials) {
      ++counts[int(mat.alpha_mode)];
      textured += mat.base_color_texture >= 0;
      single += !mat.double_sided;
    }
    std::fprintf(stderr, "%s: materials %zu (OPAQUE %zu, MASK %zu, BLEND %zu; textured %zu, single-sided %zu), "
                 "textures %zu; shader variants: %s\n", program_invocation_short_name, scene.materials.size(),
                 counts[0], counts[1], counts[2], textured, single, scene.images.size(), variants_.c_str());
  });

  gl_.CreateVertexArrays(1, &vao_);
  gl_.VertexArrayAttribFormat(vao_, 0, 3, GL_FLOAT, GL_FALSE, offsetof(Vertex, position));
  gl_.VertexArrayAttribFormat(vao_, 1, 3, GL_FLOAT, GL_FALSE, offsetof(Vertex, normal));
  gl_.VertexArrayAttribFormat(vao_, 10, 4, GL_UNSIGNED_BYTE, GL_TRUE, offsetof(Vertex, color));
  gl_.VertexArrayBindingDivisor(vao_, 1, 1);
  for (GLuint c = 0; c < 4; ++c)
    gl_.VertexArrayAttribFormat(vao_, 2 + c, 4, GL_FLOAT, GL_FALSE,
                                offsetof(DrawRecord, object.model_view) + c * sizeof(glm::vec4));
  for (GLuint c = 0; c < 3; ++c)
    gl_.VertexArrayAttribFormat(vao_, 6 + c, 4, GL_FLOAT, GL_FALSE,
                                offsetof(DrawRecord, object.normal_color) + c * sizeof(glm::vec4));
  gl_.VertexArrayAttribIFormat(vao_, 9, 1, GL_UNSIGNED_INT, offsetof(DrawRecord, id_plus_one));
  gl_.VertexArrayAttribFormat(vao_, 11, 2, GL_FLOAT, GL_FALSE, offsetof(DrawRecord, object.alpha_cutoff));
  for (GLuint a = 0; a < 12; ++a) {
    gl_.VertexArrayAttribBinding(vao_, a, (a < 2 || a == 10) ? 0 : 1);
    gl_.EnableVertexArrayAttrib(vao_, a);
  }
  if (any_textured) {
    gl_.VertexArrayAttribFormat(vao_, 12, 2, GL_FLOAT, GL_FALSE, 0);
    gl_.VertexArrayAttribBinding(vao_, 12, 2);
    gl_.EnableVertexArrayAttrib(vao_, 12);
    upload_textures(scene, used_texture);
  }
  bind_segment(0);
}

void SceneRenderer::bind_segment(uint32_t s) {
  const Segment& sg = segments_.at(s);
  gl_.VertexArrayVertexBuffer(vao_, 0, sg.vertices, 0, 28);
  gl_.VertexArrayElementBuffer(vao_, sg.indices);
  if (sg.uvs) gl_.VertexArrayVertexBuffer(vao_, 2, sg.uvs, 0, sizeof(glm::vec2));
}

void SceneRenderer::upload_textures(const Scene& scene, const std::vector<uint8_t>& used_texture) {
  textures_.assign(scene.images.size(), 0);
  samplers_.assign(scene.textures.size(), 0);
  texture_image_.assign(scene.textures.size(), 0);
  for (size_t t = 0; t < scene.textures.size(); ++t) {
    if (!used_texture[t]) continue;
    const Texture& tex = scene.textures[t];
    texture_image_[t] = tex.image;
    GLuint& gl_tex = textures_[tex.image];
    if (gl_tex == 0) {
      const Image& img = scene.images[tex.image];
      if (img.width <= 0 || img.height <= 0 || img.rgba.size() != size_t(img.width) * size_t(img.height) * 4)
        throw std::runtime_error("SceneRenderer: image " + std::to_string(tex.image) + " is not " +
                                 std::to_string(img.width) + "x" + std::to_string(img.height) + " RGBA8");
      const int levels = 1 + int(std::floor(std::log2(double(std::max(img.width, img.height)))));
      gl_.CreateTextures(GL_TEXTURE_2D, 1, &gl_tex);
      gl_.TextureStorage2D(gl_tex, levels, GL_RGBA8, img.width, img.height);
      gl_.PixelStorei(GL_UNPACK_ALIGNMENT, 1);
      // Row 0 of the image (its top) goes to t = 0: glTF's uv (0, 0) is the top-left texel.
      gl_.TextureSubImage2D(gl_tex, 0, 0, 0, img.width, img.height, GL_RGBA, GL_UNSIGNED_BYTE, img.rgba.data());
      gl_.GenerateTextureMipmap(gl_tex);
    }
    const Sampler& s = tex.sampler;
    gl_.CreateSamplers(1, &samplers_[t]);
    gl_.SamplerParameteri(samplers_[t], GL_TEXTURE_MAG_FILTER, s.mag_filter == -1 ? GL_LINEAR : s.mag_filter);
    gl_.SamplerParameteri(samplers_[t], GL_TEXTURE_MIN_FILTER,
                          s.min_filter == -1 ? GL_LINEAR_MIPMAP_LINEAR : s.min_filter);
    gl_.SamplerParameteri(samplers_[t], GL_TEXTURE_WRAP_S, s.wrap_s);
    gl_.SamplerParameteri(samplers_[t], GL_TEXTURE_WRAP_T, s.wrap_t);
  }
}

void SceneRenderer::compile(Mode mode, unsigned bits) {
  static_assert(sizeof(programs_[0]) / sizeof(programs_[0][0]) == kVariants);
  Program& p = programs_[int(mode)][bits];
  if (p.id) return;
  const std::string head = defines(mode, bits);
  p.id = link_program(gl_, head + kVertexBody, head + kFragmentBody);
  p.projection_loc = gl_.GetUniformLocation(p.id, "u_projection");
}

SceneRenderer::~SceneRenderer() {
  for (auto& mode : programs_)
    for (const Program& p : mode)
      if (p.id) gl_.DeleteProgram(p.id);
  gl_.DeleteVertexArrays(1, &vao_);
  const GLuint buffers[] = {record_buf_, indirect_buf_};
  for (GLuint b : buffers)
    if (b) gl_.DeleteBuffers(1, &b);
  for (const Segment& sg : segments_)
    for (GLuint b : {sg.vertices, sg.indices, sg.uvs})
      if (b) gl_.DeleteBuffers(1, &b);
  for (GLuint t : textures_)
    if (t) gl_.DeleteTextures(1, &t);
  for (GLuint s : samplers_)
    if (s) gl_.DeleteSamplers(1, &s);
}

void SceneRenderer::begin_frame(const Camera& cam, bool clear_color, bool defer_blended) {
  float bg[4];
  for (int c = 0; c < 4; ++c) bg[c] = kBackgroundRgba8[c] / 255.0f;
  begin(cam, clear_color ? bg : nullptr);
  defer_blended_ = defer_blended;
}

void SceneRenderer::begin_id_frame(const Camera& cam) {
  const float zero[4] = {0, 0, 0, 0};
  begin(cam, zero);
}

void SceneRenderer::begin(const Camera& cam, const float clear_rgba[4]) {
  view_rotation_ = cam.view_rotation();
  eye_ = cam.eye;
  defer_blended_ = false;
  blended_.clear();
  const glm::mat4 projection(cam.projection());
  for (auto& mode : programs_)
    for (const Program& p : mode)
      if (p.id) gl_.ProgramUniformMatrix4fv(p.id, p.projection_loc, 1, GL_FALSE, glm::value_ptr(projection));
  if (++frame_ == 0) {  // stamps wrapped: forget them all
    std::fill(object_frame_.begin(), object_frame_.end(), 0);
    frame_ = 1;
  }

  gl_.DepthMask(GL_TRUE);
  gl_.ColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
  GLbitfield mask = GL_DEPTH_BUFFER_BIT;
  if (clear_rgba) {
    gl_.ClearColor(clear_rgba[0], clear_rgba[1], clear_rgba[2], clear_rgba[3]);
    mask |= GL_COLOR_BUFFER_BIT;
  }
  gl_.Clear(mask);
}

const SceneRenderer::ObjectMatrices& SceneRenderer::object_matrices(uint32_t object) {
  ObjectMatrices& m = object_matrices_[object];
  if (object_frame_[object] == frame_) return m;
  object_frame_[object] = frame_;
  glm::dmat4 relative = transforms_[object];
  relative[3] -= glm::dvec4(eye_, 0.0);  // translate by -eye in double, before rounding
  const glm::dmat4 model_view = view_rotation_ * relative;
  // inverse transpose of (rotation x model) = rotation x inverse transpose of model
  const glm::dmat3 normal_matrix = glm::dmat3(view_rotation_) * normal_world_[object];
  const ObjectLook& look = looks_[object];
  m.model_view = glm::mat4(model_view);
  for (int c = 0; c < 3; ++c) m.normal_color[c] = glm::vec4(glm::vec3(normal_matrix[c]), look.color[c]);
  m.alpha_cutoff = {look.color.a, look.cutoff};
  return m;
}

void SceneRenderer::check_items(std::span<const uint32_t> item_indices) const {
  for (uint32_t item : item_indices)
    if (item >= item_draws_.size())
      throw std::out_of_range("SceneRenderer: item " + std::to_string(item) + " out of range (" +
                              std::to_string(item_draws_.size()) + " items)");
}

void SceneRenderer::check_nodes(std::span<const uint32_t> node_ids) const {
  for (uint32_t id : node_ids)
    if (id >= hierarchy_.size())
      throw std::out_of_range("SceneRenderer: node " + std::to_string(id) + " out of range (" +
                              std::to_string(hierarchy_.size()) + " nodes)");
}

// Batch key: variant bits (of this mode), texture + 1, culling; kBlendKey marks BLEND draws.
uint64_t SceneRenderer::batch_key(uint32_t object, Mode mode, bool lod) const {
  const ObjectLook& look = looks_[object];
  unsigned bits = lod ? lod_bits(look.bits) : look.bits;
  if (bits & kBlend) return kBlendKey;
  bits = mode_bits(mode, bits);
  const uint64_t texture = (bits & kTextured) ? uint64_t(look.texture) + 1 : 0;
  return uint64_t(bits) << 40 | texture << 8 | look.cull;
}

void SceneRenderer::add_item(uint32_t item, uint32_t id_plus_one, Mode mode, DrawStats& stats) {
  add_draw(item_draws_[item], id_plus_one, mode, false, stats);
}

void SceneRenderer::add_draw(const ItemDraw& d, uint32_t id_plus_one, Mode mode, bool lod, DrawStats& stats) {
  const uint64_t key = batch_key(d.object, mode, lod);
  if (key == kBlendKey) {
    if (mode != Mode::Shaded) return;  // never an occluder, not in the item buffer
    // The key is set when they are drawn; until then it says whether the draw is a LOD's.
    blended_.push_back({lod ? 1u : 0u, d, id_plus_one});
    return;
  }
  pending_.push_back({key, d, id_plus_one});
  stats.items += 1;
  stats.triangles += d.index_count / 3;
}

std::pair<SceneRenderer::DrawPlace, SceneRenderer::DrawPlace> SceneRenderer::draw_places(const Renderables& r,
                                                                                         uint32_t id) {
  if (id >= r.count())
    throw std::out_of_range("SceneRenderer: renderable " + std::to_string(id) + " out of range (" +
                            std::to_string(r.count()) + ")");
  // Collected as draw_renderables collects it, then taken back out.
  const size_t pending = pending_.size(), blended = blended_.size();
  DrawStats unused;
  add_renderable(r, id, Mode::Shaded, unused);
  const uint64_t rank = (uint64_t(hierarchy_.node(r.node_of(id)).first_item) << 8 | r.level_of(id)) << 20;
  DrawPlace first{~uint64_t(0), ~0u, 1e300, ~uint64_t(0)}, last{0, 0, -1e300, 0};
  for (size_t i = pending; i < pending_.size(); ++i) {
    const Pending& p = pending_[i];
    const glm::dvec3 d = centers_[p.draw.object] - eye_;
    const DrawPlace place{p.key, p.draw.segment, glm::dot(d, d), rank + (i - pending)};
    first = std::min(first, place);
    last = std::max(last, place);
  }
  pending_.resize(pending);
  blended_.resize(blended);
  return {first, last};
}

DrawStats SceneRenderer::draw_renderables(const Renderables& r, std::span<const uint32_t> ids, Mode mode) {
  std::vector<std::pair<uint64_t, uint32_t>> order;  // (first item << 8 | level, id)
  order.reserve(ids.size());
  for (uint32_t id : ids) {
    if (id >= r.count())
      throw std::out_of_range("SceneRenderer: renderable " + std::to_string(id) + " out of range (" +
                              std::to_string(r.count()) + ")");
    const uint32_t node = r.node_of(id);
    order.emplace_back(uint64_t(hierarchy_.node(node).first_item) << 8 | r.level_of(id), id);
  }
  std::sort(order.begin(), order.end());
  DrawStats stats;
  for (auto [key, id] : order) add_renderable(r, id, mode, stats);
  return submit(mode, stats);
}

void SceneRenderer::add_renderable(const Renderables& r, uint32_t id, Mode mode, DrawStats& stats) {
  const uint32_t node = r.node_of(id), level = r.level_of(id);
  const HNode& n = hierarchy_.node(node);
  if (n.leaf() && level > 0 && !lod_draws_.empty()) {
    for (uint32_t i = n.first_item; i < n.first_item + n.item_count; ++i) {
      ItemDraw d = lod_draws_[item_slot_[i] * kLeafLodLevels + level - 1];
      d.object = item_draws_[i].object;
      add_draw(d, i + 1, mode, true, stats);
    }
  } else if (!n.leaf() && !hlod_draws_.empty() && hlod_of_node_[node] != kNoNode) {
    add_draw(hlod_draws_[hlod_of_node_[node]], node + 1, mode, false, stats);  // its look: vertex colours
  } else {
    for (uint32_t i = n.first_item; i < n.first_item + n.item_count; ++i) add_item(i, i + 1, mode, stats);
  }
}

bool SceneRenderer::holds_blended(const Renderables& r, uint32_t id) const {
  if (!has_blended_) return false;
  if (id >= r.count())
    throw std::out_of_range("SceneRenderer: renderable " + std::to_string(id) + " out of range (" +
                            std::to_string(r.count()) + ")");
  const uint32_t node = r.node_of(id);
  const HNode& n = hierarchy_.node(node);
  if (!n.leaf() && !hlod_draws_.empty() && hlod_of_node_[node] != kNoNode) return false;  // HLODs are opaque
  for (uint32_t i = n.first_item; i < n.first_item + n.item_count; ++i)
    if (looks_[item_draws_[i].object].bits & kBlend) return true;
  return false;
}

void SceneRenderer::query_renderables(const Renderables& r, std::span<const uint32_t> ids,
                                      std::span<const GLuint> queries, GLenum depth_func) {
  if (queries.size() != ids.size() && queries.size() != 1)
    throw std::invalid_argument("SceneRenderer::query_renderables: " + std::to_string(ids.size()) + " renderables but " +
                                std::to_string(queries.size()) + " queries");
  if (ids.empty()) return;
  // Each query's depth-only draws (BLEND items left out, as DepthOnly does), in batch-key order:
  // one renderable's, or (one query) all of them; query_ends_[k] ends query k's draws.
  pending_.clear();
  query_ends_.clear();
  const bool one_query = queries.size() == 1;
  const auto by_key = [](const Pending& a, const Pending& b) { return a.key < b.key; };
  DrawStats unused;
  for (uint32_t id : ids) {
    if (id >= r.count())
      throw std::out_of_range("SceneRenderer: renderable " + std::to_string(id) + " out of range (" +
                              std::to_string(r.count()) + ")");
    const size_t begin = one_query ? 0 : pending_.size();
    add_renderable(r, id, Mode::DepthOnly, unused);
    if (one_query) continue;
    std::stable_sort(pending_.begin() + ptrdiff_t(begin), pending_.end(), by_key);
    query_ends_.push_back(pending_.size());
  }
  if (one_query) {
    std::stable_sort(pending_.begin(), pending_.end(), by_key);
    query_ends_.push_back(pending_.size());
  }
  // The occluders' state without their offset, depth writes off and (GL_GEQUAL) ties passing:
  // where this geometry lies on the depth it (or anything at the same depth) wrote, it still shows.
  query_pending(queries, depth_func);
}

void SceneRenderer::query_pending(std::span<const GLuint> queries, GLenum depth_func) {
  upload_draws(pending_);
  part_triangles_ = flush_triangles_.value_or(kFlushTriangles);  // queries: parts as before
  gl_.ColorMask(GL_FALSE, GL_FALSE, GL_FALSE, GL_FALSE);
  gl_.DepthMask(GL_FALSE);
  gl_.Enable(GL_DEPTH_TEST);
  gl_.DepthFunc(depth_func);
  gl_.BindVertexArray(vao_);
  gl_.BindBuffer(GL_DRAW_INDIRECT_BUFFER, indirect_buf_);
  RunState bound;
  bound.segment = segments_.size() > 1 ? ~0u : 0;
  size_t b = 0;
  for (size_t k = 0; k < queries.size(); ++k) {
    gl_.BeginQuery(GL_SAMPLES_PASSED, queries[k]);
    draw_runs(pending_, b, query_ends_[k], Mode::DepthOnly, bound);
    gl_.EndQuery(GL_SAMPLES_PASSED);
    b = query_ends_[k];
  }
  pending_.clear();
  if (bound.cull != kCullNone) {
    gl_.Disable(GL_CULL_FACE);
    gl_.FrontFace(GL_CCW);
  }
  gl_.DepthFunc(GL_GREATER);
  gl_.DepthMask(GL_TRUE);
}

bool SceneRenderer::item_blended(uint32_t item) const {
  if (item >= item_draws_.size())
    throw std::out_of_range("SceneRenderer: item " + std::to_string(item) + " out of range (" +
                            std::to_string(item_draws_.size()) + ")");
  return (looks_[item_draws_[item].object].bits & kBlend) != 0;
}

void SceneRenderer::query_blended_items(std::span<const uint32_t> items, std::span<const GLuint> queries) {
  if (queries.size() != items.size())
    throw std::invalid_argument("SceneRenderer::query_blended_items: " + std::to_string(items.size()) +
                                " items but " + std::to_string(queries.size()) + " queries");
  if (items.empty()) return;
  pending_.clear();
  query_ends_.clear();
  for (uint32_t item : items) {
    if (!item_blended(item))
      throw std::invalid_argument("SceneRenderer::query_blended_items: item " + std::to_string(item) +
                                  " is not BLEND");
    const ItemDraw& d = item_draws_[item];
    pending_.push_back({uint64_t(looks_[d.object].cull), d, item + 1});  // the plain depth program
    query_ends_.push_back(pending_.size());
  }
  query_pending(queries, GL_GREATER);  // as the Shaded pass draws glass: ties fail
}

DrawStats SceneRenderer::draw_items(std::span<const uint32_t> item_indices, Mode mode) {
  check_items(item_indices);
  DrawStats stats;
  for (uint32_t item : item_indices) add_item(item, item + 1, mode, stats);
  return submit(mode, stats);
}

DrawStats SceneRenderer::draw_nodes(std::span<const uint32_t> node_ids, Mode mode) {
  check_nodes(node_ids);
  DrawStats stats;
  for (uint32_t id : node_ids) {
    const HNode& n = hierarchy_.node(id);
    for (uint32_t i = n.first_item; i < n.first_item + n.item_count; ++i) add_item(i, i + 1, mode, stats);
  }
  return submit(mode, stats);
}

DrawStats SceneRenderer::draw_nodes_ids(std::span<const uint32_t> node_ids) {
  check_nodes(node_ids);
  DrawStats stats;
  for (uint32_t id : node_ids) {
    const HNode& n = hierarchy_.node(id);
    for (uint32_t i = n.first_item; i < n.first_item + n.item_count; ++i) add_item(i, id + 1, Mode::ItemIds, stats);
  }
  return submit(Mode::ItemIds, stats);
}

DrawStats SceneRenderer::end_frame() { return draw_blended(); }

DrawStats SceneRenderer::submit(Mode mode, DrawStats stats) {
  if (!pending_.empty()) {
    // Batches by key, each batch by segment, then near to far (the squared distance from the eye
    // to the object's box centre), then the given order: the nearer surfaces fill the depth
    // buffer first, so llvmpipe skips shading the fragments they hide (render time per frame
    // ~0.93x on the saw and the duplex at 1024^2, paired runs). The order of any two draws
    // depends only on them and the camera, so every renderer (reference, RVG, any subset of the
    // scene) resolves depth ties between them alike.
    batch_order_.clear();
    for (uint32_t i = 0; i < pending_.size(); ++i) {
      const Pending& p = pending_[i];
      const glm::dvec3 d = centers_[p.draw.object] - eye_;
      batch_order_.push_back({p.key, p.draw.segment, glm::dot(d, d), i});
    }
    std::sort(batch_order_.begin(), batch_order_.end(), [](const BatchOrder& a, const BatchOrder& b) {
      return std::tie(a.key, a.segment, a.distance2, a.index) < std::tie(b.key, b.segment, b.distance2, b.index);
    });
    sorted_.clear();
    for (const BatchOrder& o : batch_order_) sorted_.push_back(pending_[o.index]);
    draw_batches(sorted_, mode, false);
    pending_.clear();
  }
  if (mode == Mode::Shaded && !defer_blended_) stats += draw_blended();
  return stats;
}

DrawStats SceneRenderer::draw_blended() {
  DrawStats stats;
  if (blended_.empty()) return stats;
  // Back to front: decreasing squared distance of the object's box centre, ties by id, then
  // by collection order (an HLOD and an item never share an id + 1 and an object).
  blend_order_.clear();
  for (uint32_t i = 0; i < blended_.size(); ++i) {
    const glm::dvec3 d = centers_[blended_[i].draw.object] - eye_;
    blend_order_.emplace_back(-glm::dot(d, d), i);
  }
  std::sort(blend_order_.begin(), blend_order_.end(), [&](const auto& a, const auto& b) {
    if (a.first != b.first) return a.first < b.first;
    if (blended_[a.second].id_plus_one != blended_[b.second].id_plus_one)
      return blended_[a.second].id_plus_one < blended_[b.second].id_plus_one;
    return a.second < b.second;
  });
  sorted_.clear();
  for (const auto& [dist, i] : blend_order_) {
    Pending p = blended_[i];
    const ObjectLook& look = looks_[p.draw.object];
    const unsigned bits = mode_bits(Mode::Shaded, p.key ? lod_bits(look.bits) : look.bits);
    p.key = uint64_t(bits) << 40 | ((bits & kTextured) ? uint64_t(look.texture) + 1 : 0) << 8 | look.cull;
    sorted_.push_back(p);
    stats.items += 1;
    stats.triangles += p.draw.index_count / 3;
  }
  blended_.clear();
  draw_batches(sorted_, Mode::Shaded, true);
  return stats;
}

void SceneRenderer::upload_draws(std::span<const Pending> draws) {
  records_.clear();
  commands_.clear();
  for (const Pending& p : draws) {
    records_.push_back({object_matrices(p.draw.object), p.id_plus_one});
    commands_.push_back({p.draw.index_count, 1, p.draw.first_index, p.draw.base_vertex, uint32_t(commands_.size())});
  }
  // Buffers keep their storage between calls; they only grow (never a per-frame allocation).
  const size_t record_bytes = records_.size() * sizeof(DrawRecord);
  const size_t command_bytes = commands_.size() * sizeof(IndirectCommand);
  if (record_bytes > record_capacity_) {
    if (record_buf_) gl_.DeleteBuffers(1, &record_buf_);
    record_capacity_ = std::max(record_bytes + record_bytes / 2, size_t(64) << 10);
    gl_.CreateBuffers(1, &record_buf_);
    gl_.NamedBufferStorage(record_buf_, GLsizeiptr(record_capacity_), nullptr, GL_DYNAMIC_STORAGE_BIT);
    gl_.VertexArrayVertexBuffer(vao_, 1, record_buf_, 0, sizeof(DrawRecord));
  }
  if (command_bytes > indirect_capacity_) {
    if (indirect_buf_) gl_.DeleteBuffers(1, &indirect_buf_);
    indirect_capacity_ = std::max(command_bytes + command_bytes / 2, size_t(16) << 10);
    gl_.CreateBuffers(1, &indirect_buf_);
    gl_.NamedBufferStorage(indirect_buf_, GLsizeiptr(indirect_capacity_), nullptr, GL_DYNAMIC_STORAGE_BIT);
  }
  gl_.NamedBufferSubData(record_buf_, 0, GLsizeiptr(record_bytes), records_.data());
  gl_.NamedBufferSubData(indirect_buf_, 0, GLsizeiptr(command_bytes), commands_.data());
}

void SceneRenderer::draw_runs(std::span<const Pending> draws, size_t first, size_t last, Mode mode, RunState& bound) {
  for (size_t b = first; b < last;) {
    size_t e = b + 1;
    const uint32_t segment = draws[b].draw.segment;
    while (e < last && draws[e].key == draws[b].key && draws[e].draw.segment == segment) ++e;
    if (segment != bound.segment) {
      bind_segment(segment);
      bound.segment = segment;
    }
    const uint64_t key = draws[b].key;
    const unsigned bits = unsigned(key >> 40) & (kVariants - 1);
    const int64_t texture = int64_t((key >> 8) & 0xffffffffu) - 1;
    const int cull = int(key & 0xff);
    if (bits != bound.bits) {
      gl_.UseProgram(programs_[int(mode)][bits].id);
      bound.bits = bits;
    }
    if (texture >= 0 && texture != bound.texture) {
      gl_.BindTextureUnit(0, textures_[texture_image_[size_t(texture)]]);
      gl_.BindSampler(0, samplers_[size_t(texture)]);
      bound.texture = texture;
    }
    if (cull != bound.cull) {
      if (cull == kCullNone) {
        gl_.Disable(GL_CULL_FACE);
      } else {
        gl_.Enable(GL_CULL_FACE);
        gl_.CullFace(GL_BACK);
        gl_.FrontFace(cull == kCullBackCw ? GL_CW : GL_CCW);
      }
      bound.cull = cull;
    }
    // One indirect call per part of about part_triangles_ (see set_flush_triangles).
    for (size_t c = b; c < e;) {
      size_t d = c;
      uint64_t triangles = 0;
      do {
        triangles += draws[d++].draw.index_count / 3;
      } while (d < e && (part_triangles_ == 0 || unflushed_triangles_ + triangles < part_triangles_));
      gl_.MultiDrawElementsIndirect(GL_TRIANGLES, GL_UNSIGNED_INT,
                                    reinterpret_cast<const void*>(c * sizeof(IndirectCommand)), GLsizei(d - c), 0);
      unflushed_triangles_ += triangles;
      if (part_triangles_ != 0 && unflushed_triangles_ >= part_triangles_) {
        gl_.Flush();
        unflushed_triangles_ = 0;
      }
      c = d;
    }
    b = e;
  }
}

uint32_t SceneRenderer::part_for(std::span<const Pending> draws) const {
  if (flush_triangles_) return *flush_triangles_;
  uint64_t triangles = 0;
  for (const Pending& p : draws) triangles += p.draw.index_count / 3;
  return flush_part(triangles);
}

void SceneRenderer::draw_batches(std::span<const Pending> draws, Mode mode, bool blended) {
  upload_draws(draws);
  part_triangles_ = part_for(draws);
  const bool color = mode != Mode::DepthOnly;
  const bool offset = !color && occluder_offset_;  // see set_occluder_offset()
  if (offset) {
    gl_.Enable(GL_POLYGON_OFFSET_FILL);
    gl_.PolygonOffset(-kOccluderSlopeOffset, -kOccluderSlopeOffset);
  }
  gl_.ColorMask(color, color, color, color);
  gl_.DepthMask(blended ? GL_FALSE : GL_TRUE);
  gl_.Enable(GL_DEPTH_TEST);
  gl_.DepthFunc(GL_GREATER);
  if (blended) {
    gl_.Enable(GL_BLEND);
    gl_.BlendFuncSeparate(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA, GL_ONE, GL_ONE_MINUS_SRC_ALPHA);
  }
  gl_.BindVertexArray(vao_);
  gl_.BindBuffer(GL_DRAW_INDIRECT_BUFFER, indirect_buf_);
  RunState bound;
  bound.segment = segments_.size() > 1 ? ~0u : 0;  // bound at construction
  draw_runs(draws, 0, draws.size(), mode, bound);
  // Leave the defaults for other GL users (BoxQuerier, HZB readback).
  if (offset) gl_.Disable(GL_POLYGON_OFFSET_FILL);  // never on query boxes or shaded frames
  if (bound.cull != kCullNone) {
    gl_.Disable(GL_CULL_FACE);
    gl_.FrontFace(GL_CCW);
  }
  if (blended) {
    gl_.Disable(GL_BLEND);
    gl_.DepthMask(GL_TRUE);
  }
}

std::vector<uint32_t> ids_in_image(const Image& img) {
  std::vector<uint32_t> ids;
  uint32_t last = 0;
  for (size_t p = 0; p + 3 < img.rgba.size(); p += 4) {
    const uint32_t v = uint32_t(img.rgba[p]) | uint32_t(img.rgba[p + 1]) << 8 |
                       uint32_t(img.rgba[p + 2]) << 16 | uint32_t(img.rgba[p + 3]) << 24;
    if (v != 0 && v != last) ids.push_back(v - 1);  // runs of one id are common
    last = v;
  }
  std::sort(ids.begin(), ids.end());
  ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
  return ids;
}

}  // namespace occ
