#include "common/gl/scene_gpu.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <string>

#include <errno.h>
#include <malloc.h>

#include "common/hash.hpp"

namespace occ {

uint32_t gl_detail::pack_rgba8(glm::vec4 c) {
  uint32_t rgba = 0;
  for (int k = 0; k < 4; ++k) rgba |= uint32_t(std::lround(std::clamp(c[k], 0.0f, 1.0f) * 255.0f)) << (8 * k);
  return rgba;
}

using namespace gl_detail;

namespace {

struct Vertex {
  glm::vec3 position, normal;
  uint32_t color;  // RGBA8
};
static_assert(sizeof(Vertex) == 28 && sizeof(SceneGpu::DrawRecord) == 124);

glm::vec4 object_color(uint32_t object) {
  const uint64_t h = mix64(object + 1);
  auto channel = [&](int k) { return 0.45f + 0.5f * float((h >> (8 * k)) & 0xff) / 255.0f; };
  return {channel(0), channel(1), channel(2), 1.0f};
}


// What object o of `scene` draws with: its material's variant bits, texture, face culling and
// colour (a mild per-object colour without a material).
SceneGpu::ObjectLook look_of(const Scene& scene, uint32_t o) {
  const Object& obj = scene.objects[o];
  const Mesh& mesh = scene.meshes[obj.mesh];
  if (mesh.material != kNoMaterial && mesh.material >= scene.materials.size())
    throw std::runtime_error("SceneRenderer: mesh " + std::to_string(obj.mesh) + " has material " +
                             std::to_string(mesh.material) + " of " + std::to_string(scene.materials.size()));
  const Material* mat = scene.material_of(obj.mesh);
  SceneGpu::ObjectLook look;
  if (scene.mesh_has_colors(obj.mesh)) look.bits |= kVertexColor;
  if (mesh.flat && !(mat && mat->unlit)) look.bits |= kFlat;  // unlit: no normal to take
  const bool mirrored = glm::determinant(glm::dmat3(obj.transform)) < 0.0;
  if (!mat) {
    look.color = object_color(o);
    look.cull = kCullNone;
    return look;
  }
  look.color = mat->object_color ? glm::vec4(glm::vec3(object_color(o)), mat->base_color.a) : mat->base_color;
  look.cutoff = mat->alpha_cutoff;
  look.cull = mat->double_sided ? kCullNone : mirrored ? kCullBackCw : kCullBackCcw;
  if (mat->alpha_mode == AlphaMode::Mask) look.bits |= kMask;
  if (mat->alpha_mode == AlphaMode::Blend) look.bits |= kBlend;
  if (mat->unlit) look.bits |= kUnlit;
  if (mat->base_color_texture >= 0 && scene.mesh_has_uvs(obj.mesh)) {
    if (size_t(mat->base_color_texture) >= scene.textures.size() ||
        scene.textures[size_t(mat->base_color_texture)].image >= scene.images.size())
      throw std::runtime_error("SceneRenderer: material '" + mat->name + "' has texture " +
                               std::to_string(mat->base_color_texture) + " without an image");
    look.bits |= kTextured;
    look.texture = mat->base_color_texture;
  }
  return look;
}

// Geometry goes to GL in segments (SceneUpload): a segment is staged on the CPU until it holds
// about segment_bytes, then becomes its own vertex/index/uv buffers. With SceneUpload::release
// each mesh's CPU arrays are freed as soon as they are staged, so the CPU geometry shrinks as the
// driver's copy grows (plant:40: 6.5 GB a process with one buffer and kept arrays, see
// docs/scale.md).
// Where each piece goes (SegmentLayout::place): a new segment unless its vertices and indices
// still fit the current one. The same with or without staging, so streaming keeps the draw order.
class SegmentLayout {
 public:
  explicit SegmentLayout(size_t segment_bytes) : limit_(std::max<size_t>(segment_bytes, 4096)) {}
  // first_index, base_vertex (within the segment) and segment of nv vertices and ni indices.
  SceneGpu::ItemDraw place(uint64_t nv, uint64_t ni, uint32_t piece) {
    if ((nv_ || ni_) && (nv_ + nv) * sizeof(Vertex) + (ni_ + ni) * sizeof(uint32_t) > limit_) {
      ++segment_;
      nv_ = ni_ = 0;
    }
    if (nv_ + nv > uint64_t(INT32_MAX)) throw std::runtime_error("SceneRenderer: more than 2^31 vertices in a mesh");
    SceneGpu::ItemDraw at{0, uint32_t(ni_), int32_t(nv_), 0, segment_, piece};
    nv_ += nv;
    ni_ += ni;
    return at;
  }

 private:
  const size_t limit_;
  uint64_t nv_ = 0, ni_ = 0;
  uint32_t segment_ = 0;
};

class SegmentStager {
 public:
  SegmentStager(const GlApi& gl, std::vector<SceneGpu::Segment>& segments, bool uvs)
      : gl_(gl), segments_(segments), with_uvs_(uvs) {}

  // Uploads what is staged when the next piece goes to segment s (SegmentLayout).
  void to_segment(uint32_t s) {
    if (s != segments_.size()) flush();
  }
  bool with_uvs() const { return with_uvs_; }
  // `bytes` of CPU geometry were freed: the heap gives its pages back now and then.
  void released(uint64_t bytes) {
    freed_since_trim_ += bytes;
    if (freed_since_trim_ >= (uint64_t(64) << 20)) {
      ::malloc_trim(0);
      freed_since_trim_ = 0;
    }
  }
  // Uploads what is staged (at least one segment in all) and frees the staging arrays.
  void finish() {
    if (!vertices.empty() || !indices.empty() || segments_.empty()) flush();
    std::vector<Vertex>().swap(vertices);
    std::vector<uint32_t>().swap(indices);
    std::vector<glm::vec2>().swap(uvs);
  }

  std::vector<Vertex> vertices;
  std::vector<uint32_t> indices;
  std::vector<glm::vec2> uvs;  // with_uvs() only: one per vertex

 private:
  void flush() {
    SceneGpu::Segment sg;
    auto create = [&](GLuint* buf, const void* data, size_t bytes) {
      gl_.CreateBuffers(1, buf);
      gl_.NamedBufferStorage(*buf, GLsizeiptr(std::max<size_t>(1, bytes)), bytes ? data : nullptr, 0);
    };
    create(&sg.vertices, vertices.data(), vertices.size() * sizeof(Vertex));
    create(&sg.indices, indices.data(), indices.size() * sizeof(uint32_t));
    if (with_uvs_) create(&sg.uvs, uvs.data(), uvs.size() * sizeof(glm::vec2));
    segments_.push_back(sg);
    vertices.clear();
    indices.clear();
    uvs.clear();
  }

  const GlApi& gl_;
  std::vector<SceneGpu::Segment>& segments_;
  const bool with_uvs_;
  uint64_t freed_since_trim_ = 0;
};

// Stages scene mesh m (uvs only where mesh_textured) and, with release, frees its CPU arrays.
void stage_mesh(SegmentStager& st, Mesh& mesh, bool textured, bool release) {
  const bool colored = mesh.colors.size() == mesh.positions.size();
  for (size_t v = 0; v < mesh.positions.size(); ++v)
    st.vertices.push_back({mesh.positions[v], v < mesh.normals.size() ? mesh.normals[v] : glm::vec3(0, 0, 1),
                           colored ? mesh.colors[v] : 0xffffffffu});
  if (st.with_uvs()) {
    const bool with_uv = textured && mesh.uvs.size() == mesh.positions.size();
    for (size_t v = 0; v < mesh.positions.size(); ++v) st.uvs.push_back(with_uv ? mesh.uvs[v] : glm::vec2(0.0f));
  }
  st.indices.insert(st.indices.end(), mesh.indices.begin(), mesh.indices.end());
  if (release) {
    const uint64_t bytes = mesh.positions.capacity() * 24 + mesh.indices.capacity() * 4 + mesh.uvs.capacity() * 8 +
                           mesh.colors.capacity() * 4;
    mesh.release_geometry();
    st.released(bytes);
  }
}

// Stages a LOD mesh: leaf LODs white (the object's colour), HLODs each vertex its source
// object's colour.
void stage_lod_mesh(SegmentStager& st, const LodMesh& m, const std::vector<SceneGpu::ObjectLook>& looks) {
  for (size_t v = 0; v < m.positions.size(); ++v) {
    uint32_t rgba = 0xffffffffu;
    if (!m.objects.empty()) {
      const uint32_t o = m.objects[v];
      rgba = pack_rgba8(o < looks.size() ? glm::vec4(glm::vec3(looks[o].color), 1.0f) : object_color(o));
    }
    st.vertices.push_back({m.positions[v], m.normals[v], rgba});
    if (st.with_uvs()) st.uvs.push_back(glm::vec2(0.0f));
  }
  st.indices.insert(st.indices.end(), m.indices.begin(), m.indices.end());
}

// The first renderer of a process logs the scene's materials and shader variants in one line.
void log_variants_once(const Scene& scene, const std::string& variants) {
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
                 counts[0], counts[1], counts[2], textured, single, scene.images.size(), variants.c_str());
  });
}

}  // namespace

struct SceneGpu::Usage {
  std::vector<uint8_t> drawn;           // per scene object: it has items
  std::vector<Aabb> object_box;         // per object (scene objects, then HLODs): its items' box
  std::vector<uint8_t> used_texture;    // per scene texture: a drawn object's
  std::vector<uint8_t> mesh_textured;   // per scene mesh: a drawn textured object's
  bool any_textured = false;
};

SceneGpu::SceneGpu(const GlApi& gl, Scene& scene, const Hierarchy& hierarchy, LodData* lod,
                   const SceneUpload& upload)
    : gl_(gl) {
  if (scene.geometry_released() && !scene.mapped)
    throw std::logic_error("SceneRenderer: the geometry of " + scene.source + " was released after an upload");
  Usage use = read_objects(scene, hierarchy);
  upload_geometry(scene, hierarchy, lod, upload, use);
  normal_world.reserve(transforms.size());
  for (const glm::dmat4& t : transforms) normal_world.push_back(glm::transpose(glm::inverse(glm::dmat3(t))));
  centers.reserve(use.object_box.size());
  for (const Aabb& b : use.object_box) centers.push_back(b.empty() ? glm::dvec3(0.0) : b.center());
  compile_variants(scene, hierarchy, use);
  log_variants_once(scene, variants);
  create_vertex_array(use.any_textured);
  if (use.any_textured) upload_textures(scene, use.used_texture);
  bind_segment(0);
}

// Each object's transform and look; which objects draw (have items), their boxes and textures.
SceneGpu::Usage SceneGpu::read_objects(const Scene& scene, const Hierarchy& hierarchy) {
  transforms.reserve(scene.objects.size());
  looks.reserve(scene.objects.size());
  for (uint32_t o = 0; o < scene.objects.size(); ++o) {
    transforms.push_back(scene.objects[o].transform);
    looks.push_back(look_of(scene, o));
  }
  Usage use;
  use.object_box.resize(scene.objects.size());
  use.drawn.assign(scene.objects.size(), 0);
  use.used_texture.assign(scene.textures.size(), 0);
  use.mesh_textured.assign(scene.meshes.size(), 0);
  for (const Item& it : hierarchy.items()) {
    use.object_box[it.object].grow(it.box);
    use.drawn[it.object] = 1;
  }
  for (uint32_t o = 0; o < scene.objects.size(); ++o)
    if (use.drawn[o] && (looks[o].bits & kTextured)) {
      use.used_texture[size_t(looks[o].texture)] = 1;
      use.mesh_textured[scene.objects[o].mesh] = 1;
      use.any_textured = true;
    }
  return use;
}

// Stages the scene meshes, then the LOD meshes (cluster LODs, then HLODs by node id), in
// segments; then the item table. An HLOD gets a pseudo-object (its origin, an opaque lit
// double-sided white look, its node's box).
void SceneGpu::upload_geometry(Scene& scene, const Hierarchy& hierarchy, LodData* lod, const SceneUpload& upload,
                               Usage& use) {
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
      if (m->released && !lod->mapped()) throw std::logic_error("SceneRenderer: the LOD data's geometry was released");
  }
  const bool stream = streams(scene, lod, upload);
  std::optional<SegmentStager> st;
  if (!stream) st.emplace(gl_, segments, use.any_textured);
  SegmentLayout layout(upload.segment_bytes);
  // Where a piece goes: its logical segment; streaming, first index and base vertex within the piece.
  auto place = [&](uint64_t nv, uint64_t ni, uint32_t piece) {
    ItemDraw at = layout.place(nv, ni, piece);
    if (stream) at.first_index = 0, at.base_vertex = 0;
    else st->to_segment(at.segment);
    return at;
  };
  std::vector<ItemDraw> mesh_at(scene.meshes.size());  // where each scene mesh starts
  for (size_t m = 0; m < scene.meshes.size(); ++m) {
    Mesh& mesh = scene.meshes[m];
    mesh_at[m] = place(mesh.vertex_count(), mesh.triangle_count() * 3, uint32_t(m));
    if (!stream) stage_mesh(*st, mesh, use.mesh_textured[m] != 0, upload.release);
  }
  if (lod) {
    hlod_of_node.assign(hierarchy.size(), kNoNode);
    for (size_t k = 0; k < lod_meshes.size(); ++k) {
      const LodMesh& m = *lod_meshes[k];
      ItemDraw d = place(m.vertex_count(), m.triangles() * 3, uint32_t(scene.meshes.size() + k));
      d.index_count = uint32_t(m.triangles() * 3);
      if (!stream) stage_lod_mesh(*st, m, looks);
      if (lod_node[k] == kNoNode) {
        lod_draws.push_back(d);
      } else {
        const uint32_t id = lod_node[k];
        hlod_of_node[id] = uint32_t(hlod_draws.size());
        d.object = uint32_t(transforms.size());  // pseudo-object: translation to the origin
        glm::dmat4 t(1.0);
        t[3] = glm::dvec4(m.origin, 1.0);
        transforms.push_back(t);
        ObjectLook hlod_look;  // opaque, lit, double-sided, white x vertex colours
        hlod_look.bits = kVertexColor;
        looks.push_back(hlod_look);
        use.object_box.push_back(hierarchy.node(id).box);
        hlod_draws.push_back(d);
      }
      if (upload.release && !stream) {
        const uint64_t bytes = m.positions.capacity() * 24 + m.objects.capacity() * 4 + m.indices.capacity() * 4;
        lod->release(m);
        st->released(bytes);
      }
    }
    item_slot = lod->item_slots();
  }
  if (st) st->finish();
  if (upload.release && !stream) ::malloc_trim(0);
  item_draws.reserve(hierarchy.items().size());
  for (const Item& it : hierarchy.items()) {
    const uint32_t mesh = scene.objects[it.object].mesh;
    const MeshCluster& cl = scene.meshes[mesh].clusters[it.cluster];
    const ItemDraw& at = mesh_at[mesh];
    item_draws.push_back(
        {cl.index_count, at.first_index + cl.first_index, at.base_vertex, it.object, at.segment, at.piece});
  }
  if (stream) start_pool(scene, lod, std::move(lod_meshes), upload, use.mesh_textured, use.any_textured);
}

// The variants the scene uses, compiled: full detail with its materials; LODs untextured;
// HLODs plain.
void SceneGpu::compile_variants(const Scene& scene, const Hierarchy& hierarchy, const Usage& use) {
  std::vector<uint8_t> used[3];
  for (auto& u : used) u.assign(kVariants, 0);
  auto mark = [&](unsigned bits) {
    used[0][bits] = 1;
    if (!(bits & kBlend)) {
      used[1][mode_bits(DrawMode::DepthOnly, bits)] = 1;
      used[2][mode_bits(DrawMode::ItemIds, bits)] = 1;
    }
  };
  for (uint32_t o = 0; o < scene.objects.size(); ++o)
    if (use.drawn[o]) {
      mark(looks[o].bits);
      if (!lod_draws.empty()) mark(lod_bits(looks[o].bits));
      has_blended |= (looks[o].bits & kBlend) != 0;
    }
  if (!hlod_draws.empty()) mark(kVertexColor);
  if (hierarchy.items().empty()) mark(0);
  static const char* const kModeName[3] = {"shaded", "depth", "ids"};
  for (int m = 0; m < 3; ++m) {
    variants += std::string(m ? "; " : "") + kModeName[m] + ":";
    bool first = true;
    for (unsigned bits = 0; bits < kVariants; ++bits)
      if (used[m][bits]) {
        Program& p = programs[m][bits];
        p.id = link_scene_program(gl_, DrawMode(m), bits);
        p.projection_loc = gl_.GetUniformLocation(p.id, "u_projection");
        p.sections_loc = gl_.GetUniformLocation(p.id, "u_sections");
        variants += std::string(first ? " " : ", ") + variant_name(bits);
        first = false;
      }
  }
}

// Attributes 0, 1, 10 per vertex (binding 0), 2..9 and 11 per draw (binding 1, divisor 1), 12
// the uv (binding 2) when textured.
void SceneGpu::create_vertex_array(bool textured) {
  gl_.CreateVertexArrays(1, &vao);
  gl_.VertexArrayAttribFormat(vao, 0, 3, GL_FLOAT, GL_FALSE, offsetof(Vertex, position));
  gl_.VertexArrayAttribFormat(vao, 1, 3, GL_FLOAT, GL_FALSE, offsetof(Vertex, normal));
  gl_.VertexArrayAttribFormat(vao, 10, 4, GL_UNSIGNED_BYTE, GL_TRUE, offsetof(Vertex, color));
  gl_.VertexArrayBindingDivisor(vao, 1, 1);
  for (GLuint c = 0; c < 4; ++c)
    gl_.VertexArrayAttribFormat(vao, 2 + c, 4, GL_FLOAT, GL_FALSE,
                                offsetof(DrawRecord, object.model_view) + c * sizeof(glm::vec4));
  for (GLuint c = 0; c < 3; ++c)
    gl_.VertexArrayAttribFormat(vao, 6 + c, 4, GL_FLOAT, GL_FALSE,
                                offsetof(DrawRecord, object.normal_color) + c * sizeof(glm::vec4));
  gl_.VertexArrayAttribIFormat(vao, 9, 1, GL_UNSIGNED_INT, offsetof(DrawRecord, id_plus_one));
  gl_.VertexArrayAttribFormat(vao, 11, 2, GL_FLOAT, GL_FALSE, offsetof(DrawRecord, object.alpha_cutoff));
  for (GLuint a = 0; a < 12; ++a) {
    gl_.VertexArrayAttribBinding(vao, a, (a < 2 || a == 10) ? 0 : 1);
    gl_.EnableVertexArrayAttrib(vao, a);
  }
  if (textured) {
    gl_.VertexArrayAttribFormat(vao, 12, 2, GL_FLOAT, GL_FALSE, 0);
    gl_.VertexArrayAttribBinding(vao, 12, 2);
    gl_.EnableVertexArrayAttrib(vao, 12);
  }
}

void SceneGpu::bind_segment(uint32_t s) const {
  if (pool) {
    gl_.VertexArrayVertexBuffer(vao, 0, pool->buffer(), 0, sizeof(Vertex));
    gl_.VertexArrayElementBuffer(vao, pool->buffer());
    if (pool->uv_buffer()) gl_.VertexArrayVertexBuffer(vao, 2, pool->uv_buffer(), 0, sizeof(glm::vec2));
    return;
  }
  const Segment& sg = segments.at(s);
  gl_.VertexArrayVertexBuffer(vao, 0, sg.vertices, 0, sizeof(Vertex));
  gl_.VertexArrayElementBuffer(vao, sg.indices);
  if (sg.uvs) gl_.VertexArrayVertexBuffer(vao, 2, sg.uvs, 0, sizeof(glm::vec2));
}

void SceneGpu::bind_texture(size_t texture) const {
  gl_.BindTextureUnit(0, textures_[texture_image_[texture]]);
  gl_.BindSampler(0, samplers_[texture]);
}

void SceneGpu::upload_textures(const Scene& scene, const std::vector<uint8_t>& used_texture) {
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

SceneGpu::~SceneGpu() {
  for (auto& mode : programs)
    for (const Program& p : mode)
      if (p.id) gl_.DeleteProgram(p.id);
  gl_.DeleteVertexArrays(1, &vao);
  for (const Segment& sg : segments)
    for (GLuint b : {sg.vertices, sg.indices, sg.uvs})
      if (b) gl_.DeleteBuffers(1, &b);
  for (GLuint t : textures_)
    if (t) gl_.DeleteTextures(1, &t);
  for (GLuint s : samplers_)
    if (s) gl_.DeleteSamplers(1, &s);
}

}  // namespace occ
