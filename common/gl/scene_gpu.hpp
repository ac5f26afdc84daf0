// The scene as SceneRenderer's draws find it on the GPU (the layout is in scene_renderer.hpp,
// "GPU layout"): geometry segments, textures and samplers, the shader variants the scene uses,
// the vertex array, and the per-object and per-item tables the draws read. Built once by the
// constructor, one named step at a time (SceneGpu::SceneGpu), then only read; the destructor
// deletes every GL object. Internal to occ_gl: SceneRenderer owns one.
//
// Contracts: the GL context is current on the calling thread for the constructor, the
// destructor and bind_*; `scene` and `lod` are only read, unless SceneUpload::release frees
// their CPU geometry as it is staged.
#pragma once
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "common/gl/geometry_pool.hpp"
#include "common/gl/gl_api.hpp"
#include "common/gl/scene_shaders.hpp"
#include "common/scene/hierarchy.hpp"
#include "common/lod/lod.hpp"
#include "common/scene/scene.hpp"

namespace occ {

namespace gl_detail {
uint32_t pack_rgba8(glm::vec4 c);  // RGBA8, r in the low byte
}  // namespace gl_detail

// How the geometry reaches GL: in segments of about segment_bytes (vertices + indices), each
// its own vertex and index buffer, staged on the CPU and uploaded when full, never the whole
// scene in one piece (llvmpipe zeroes a buffer's whole storage when it is created, so one big
// buffer would be resident next to the whole CPU geometry). With release, every mesh's CPU
// arrays (scene meshes and LOD/HLOD meshes) are freed as soon as they are staged
// (Mesh::release_geometry, LodData::release): the driver's copy is then the only one, and
// what stays on the CPU is what culling needs (objects, clusters and their boxes, triangle
// counts, the LOD errors and tables). start_scene_gl does this for the processes. Draws keep
// their order; a run of one batch key is split where the segment changes.
//
// The geometry streams instead (GeometryPool) where the scene was loaded lazily (Scene::mapped,
// LodData::mapped: its arrays in the cache files; without a budget all of it is read at once), or
// where it is larger than a budget (budget_bytes > 0; then from the CPU copies, which stay). Nothing is uploaded at
// construction unless it all fits (then all of it is, at once); every draw names its piece and
// the renderer makes pieces resident before it draws them. The draw order is unchanged: each
// draw keeps the segment the upload above would have given it (its logical segment).
struct SceneUpload {
  size_t segment_bytes = size_t(64) << 20;
  bool release = false;
  uint64_t budget_bytes = 0;  // 0: everything resident (uploaded here)
};

class SceneGpu {
 public:
  struct ItemDraw {
    uint32_t index_count, first_index;  // first_index, base_vertex: within its segment (streaming:
    int32_t base_vertex;                // within its piece; the pool adds where the piece is)
    uint32_t object;
    uint32_t segment;
    uint32_t piece;                     // scene mesh, then LOD meshes in upload order
  };
  // A piece of the geometry upload: its own vertex, index (and uv) buffers.
  struct Segment {
    GLuint vertices = 0, indices = 0, uvs = 0;
  };
  // What an object draws with (constant): material variant bits (kTextured, kMask, kBlend,
  // kUnlit, kVertexColor), texture (-1: none), face culling, colour.
  struct ObjectLook {
    uint8_t bits = 0;
    uint8_t cull = 0;  // kCullNone, kCullBackCcw, kCullBackCw
    int32_t texture = -1;
    glm::vec4 color{1.0f};  // base colour, alpha
    float cutoff = 0.5f;
  };
  struct ObjectMatrices {  // an object's per-frame data, as laid out in DrawRecord
    glm::mat4 model_view;
    glm::vec4 normal_color[3];
    glm::vec2 alpha_cutoff;
  };
  struct DrawRecord {  // per draw, read as instanced attributes (binding 1)
    ObjectMatrices object;
    uint32_t id_plus_one;
  };
  struct Program {
    GLuint id = 0;
    GLint projection_loc = -1;
    GLint sections_loc = -1;
  };

  // Uploads `scene` (its clusters as `hierarchy`'s items) and, with `lod`, its leaf LODs and
  // HLODs. Throws std::logic_error for geometry already released, std::runtime_error for a
  // material or texture that refers to nothing.
  SceneGpu(const GlApi& gl, Scene& scene, const Hierarchy& hierarchy, LodData* lod, const SceneUpload& upload);
  ~SceneGpu();
  SceneGpu(const SceneGpu&) = delete;
  SceneGpu& operator=(const SceneGpu&) = delete;

  // Binds segment s's buffers to the vertex array (streaming: the pool's arena).
  void bind_segment(uint32_t s) const;
  // The segment whose buffers draws of logical segment s read (streaming: always 0, the arena).
  uint32_t physical_segment(uint32_t s) const { return pool ? 0 : s; }
  // Binds scene texture `texture`'s image and sampler to texture unit 0.
  void bind_texture(size_t texture) const;
  const Program& program(DrawMode mode, unsigned bits) const { return programs[int(mode)][bits]; }

  // Per object (scene objects, then one pseudo-object per HLOD: a translation to its origin).
  std::vector<glm::dmat4> transforms;
  std::vector<glm::dmat3> normal_world;  // inverse transpose of the transform's 3x3
  std::vector<ObjectLook> looks;
  std::vector<glm::dvec3> centers;       // its box centre (the draw order's distances)
  std::vector<ItemDraw> item_draws;      // per hierarchy item
  std::vector<ItemDraw> lod_draws;       // per LodData cluster LOD (object filled per draw)
  std::vector<ItemDraw> hlod_draws;      // per HLOD (object = its pseudo-object)
  std::vector<uint32_t> item_slot;       // per item: LodData slot
  std::vector<uint32_t> hlod_of_node;    // per node: HLOD index or kNoNode
  Program programs[3][gl_detail::kVariants];  // [mode][variant bits]; id 0 = not compiled
  GLuint vao = 0;
  std::vector<Segment> segments;         // the geometry, in upload order (at least one; streaming: none)
  std::unique_ptr<GeometryPool> pool;    // streaming only
  bool has_blended = false;
  std::string variants;                  // e.g. "shaded: plain, blended; depth: plain; ids: plain"

 private:
  struct Usage;  // what the drawn objects use (construction only)
  Usage read_objects(const Scene& scene, const Hierarchy& hierarchy);
  void upload_geometry(Scene& scene, const Hierarchy& hierarchy, LodData* lod, const SceneUpload& upload,
                       Usage& use);
  // Streaming: the pool over every piece (scene meshes, then lod_meshes), with the loader that
  // reads a piece from the mapped cache or the CPU copy (scene_gpu_stream.cpp).
  void start_pool(const Scene& scene, const LodData* lod, std::vector<const LodMesh*> lod_meshes,
                  const SceneUpload& upload, std::vector<uint8_t> mesh_textured, bool any_textured);
  // Whether the scene streams under upload's budget.
  static bool streams(const Scene& scene, const LodData* lod, const SceneUpload& upload);
  void compile_variants(const Scene& scene, const Hierarchy& hierarchy, const Usage& use);
  void create_vertex_array(bool textured);
  void upload_textures(const Scene& scene, const std::vector<uint8_t>& used_texture);

  const GlApi& gl_;
  std::vector<GLuint> textures_;         // per scene image (0: unused)
  std::vector<GLuint> samplers_;         // per scene texture (0: unused)
  std::vector<uint32_t> texture_image_;  // per scene texture: its image
};

}  // namespace occ
