// Draws the items of a Scene/Hierarchy (object x mesh cluster) in one of three modes:
//   Shaded     the glTF material (materials in scene.hpp): base colour = factor x texture x
//              COLOR_0, lit by a headlight per fragment (a directional light along the view axis,
//              like OpenSceneGraph's default headlight; |n.l| so back faces of double-sided and
//              open CAD meshes read well) or unlit (KHR_materials_unlit);
//              MASK discards fragments with alpha < cutoff; BLEND is drawn after everything
//              opaque, back to front, with depth writes off. Geometry without a material gets a
//              mild per-object colour from a hash of the object index (double-sided, opaque);
//   DepthOnly  colour writes off, depth writes on, the cheapest shader (occluder rendering).
//              BLEND items are never drawn (they never occlude); MASK items write depth only
//              where their alpha test passes (the same test, with invariant inputs, as Shaded);
//   ItemIds    colour = id + 1 as a little-endian 32-bit RGBA8 value (item index, or node id with
//              draw_nodes_ids), 0 = nothing: an item buffer for exact visibility (ids_in_image).
//              Opaque and MASK items only: what is seen through BLEND glass counts, the glass not.
// Every mode computes gl_Position with the same invariant expression, so depth written by one
// mode is matched exactly by another. Single-sided materials (glTF doubleSided false) cull back
// faces in every mode; an object whose transform mirrors (negative determinant) has clockwise
// front faces (glTF). Front-face culling must be the same in all modes: a single-sided wall seen
// from behind is not drawn, so it must not occlude either.
//
// Draw order (z-ties resolve identically in every renderer, so a cluster frame equals the
// reference frame): a draw call's opaque and MASK draws go in batches of one shader variant,
// texture and face culling, batches ordered by that key and draws inside a batch in the order
// given (ascending item ids from items_of_nodes and draw_renderables); then its BLEND draws, by
// decreasing squared distance from the eye to their object's box centre (computed in double),
// ties by ascending id. Both orders are total orders on items, so a subset (the visible set)
// is drawn in the order the whole scene is.
//
// Only the effects a scene calls for: one shader variant per kind of material present (plain,
// textured, masked, textured+masked, blended, textured+blended, each lit or unlit) for each mode,
// compiled at construction; no texture coordinates, textures or blending state unless the
// scene has them. The first renderer of a process logs the scene's variants in one line.
//
// GPU layout (uploaded once at construction by SceneGpu, scene_gpu.hpp, in segments: see Upload):
//   vertex buffer  all meshes back to back (per segment), interleaved {vec3 position; vec3 normal; RGBA8
//                  colour} (28 bytes; attributes 0, 1, 10, binding 0); colour = COLOR_0 (white
//                  if none) or an HLOD vertex's object colour; a mesh starts at its base vertex;
//   uv buffer      vec2 per vertex (attribute 12, binding 2), only when a drawn mesh is textured;
//   index buffer   all meshes' u32 triangle lists back to back; item = one cluster range;
//   textures       one RGBA8 texture (with mipmaps) per image a drawn material uses, one sampler
//                  object per glTF texture.
// Per draw call (only what is drawn): one DrawElementsIndirectCommand per item (baseVertex = its
// mesh, firstIndex = its cluster, baseInstance = draw slot i) and one DrawRecord per item, read
// as instanced attributes (binding 1, divisor 1, so baseInstance selects record i):
//   locations 2..5  mat4 model_view      view_rotation * (model with its translation - eye),
//                                        computed in double, then rounded to float: camera-
//                                        relative, so scenes 1e7 from the origin do not crack;
//   locations 6..8  vec4 normal_color[3] normal-matrix columns (xyz), base colour (w);
//   location 11     vec2                 base colour alpha, MASK cutoff;
//   location 9      uint id + 1.
// The record and command buffers keep their storage between frames (they grow, never shrink):
// no per-frame allocation. An object's matrices are computed once per frame and reused by all
// its items.
//
// Contracts: the GlContext is current on the calling thread for every call; the context and the
// hierarchy outlive the renderer; `scene` is the one the hierarchy was built from (its clusters)
// and is only read in the constructor (meshes, materials and images go to the GPU, transforms
// are copied) unless Upload::release frees its geometry there. Invalid item or node ids throw std::out_of_range.
//
// Parts: SceneGpu (scene_gpu.hpp) uploads the scene and owns what is on the GPU; the shader
// variants are in scene_shaders.hpp; FlushSchedule (flush_schedule.hpp) says when a frame is
// flushed; this file draws (scene_renderer.cpp) and counts samples with occlusion queries
// (scene_renderer_queries.cpp). The two-pass frames' draw places are TwoPassDrawer's.
#pragma once
#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "common/camera.hpp"
#include "common/gl/context.hpp"
#include "common/gl/flush_schedule.hpp"
#include "common/gl/scene_gpu.hpp"
#include "common/scene/hierarchy.hpp"
#include "common/image.hpp"
#include "common/lod/lod.hpp"
#include "common/scene/scene.hpp"

namespace occ {

struct DrawStats {
  uint64_t items = 0;
  uint64_t triangles = 0;
  DrawStats& operator+=(const DrawStats& o) {
    items += o.items;
    triangles += o.triangles;
    return *this;
  }
};

class SceneRenderer {
 public:
  using Mode = DrawMode;
  static constexpr std::array<uint8_t, 4> kBackgroundRgba8{20, 23, 28, 255};
  // With set_occluder_offset(true), DepthOnly draws use glPolygonOffset(-this, -this).
  static constexpr float kOccluderSlopeOffset = 0.1f;

  // With `lod`, its leaf LODs and HLODs are uploaded too (draw_renderables); it must outlive
  // nothing (only read here).
  SceneRenderer(GlContext& ctx, const Scene& scene, const Hierarchy& hierarchy, const LodData* lod = nullptr);
  // How the geometry reaches GL (SceneUpload, scene_gpu.hpp): in segments, and with release
  // the CPU arrays freed as they are staged.
  using Upload = SceneUpload;
  SceneRenderer(GlContext& ctx, Scene& scene, const Hierarchy& hierarchy, LodData* lod, const Upload& upload);
  ~SceneRenderer();
  SceneRenderer(const SceneRenderer&) = delete;
  SceneRenderer& operator=(const SceneRenderer&) = delete;

  // Occluders for a later query pass of the same depth buffer (the switch's and the occlusion
  // server's OR): DepthOnly draws go a tenth of a pixel's depth slope farther back (reverse-Z:
  // glPolygonOffset(-0.1, -0.1), switched off again after each draw). llvmpipe rasterises a
  // sliver seen almost edge-on at depths up to ~1e-4 (relative) in front of its own vertices,
  // beyond the query box's 1e-5 padding, so an occluder could hide its own box from the next HC
  // although brute force shows it (a few pixels, seen on the duplex layout walk and the city
  // walk). Off by default: a renderer that queries each node before drawing
  // it (CHC, stop-and-wait) does not need it, and toggling the state per draw costs llvmpipe.
  void set_occluder_offset(bool on) { occluder_offset_ = on; }

  // When draws are flushed mid-frame (flush_schedule.hpp): fixed parts of
  // FlushSchedule::kMaxPart at construction.
  FlushSchedule& flush_schedule() { return flush_; }
  void set_flush_triangles(uint32_t n) { flush_.request(n); }
  void set_flush_automatic() { flush_.request(std::nullopt); }

  // Starts a frame for `cam`: clears depth to 0 (far) and, if clear_color, colour to
  // kBackgroundRgba8; forgets the previous frame's per-object transforms. Each Shaded draw call
  // draws its BLEND items at its end, unless defer_blended: then they wait for end_frame() (for
  // renderers that draw a frame in many calls, e.g. front to back, one leaf at a time).
  void begin_frame(const Camera& cam, bool clear_color, bool defer_blended = false);
  // begin_frame for an item buffer: colour cleared to 0 (= no id).
  void begin_id_frame(const Camera& cam);

  // Draws the given items (indices into hierarchy.items()) in this order; ItemIds writes
  // item index + 1. Returns {items, triangles} drawn.
  DrawStats draw_items(std::span<const uint32_t> item_indices, Mode mode);
  // All items of each node's contiguous range [first_item, first_item + item_count).
  DrawStats draw_nodes(std::span<const uint32_t> node_ids, Mode mode);
  // Renderable ids (lod.hpp): leaves at level 0 draw their items, leaves at level l their items'
  // level-l LODs with the objects' transforms and colours, interior nodes their HLOD (per-vertex
  // colours of the source objects). Collected by the node's first item, then level — for
  // level-0 leaves exactly ascending item order, as everywhere else; drawn by batch key, segment,
  // near to far, then that order (submit), so z-ties resolve identically in every renderer.
  // Without LOD data uploaded, LOD ids fall back to full detail. ItemIds: a leaf at any level
  // writes its item index + 1, an HLOD items().size() + node id + 1 (an item buffer of a tau
  // frame, render_client --images items; frame_diff --items reads it).
  DrawStats draw_renderables(const Renderables& r, std::span<const uint32_t> ids, Mode mode);
  // ItemIds rendering of whole nodes, each in colour node id + 1.
  DrawStats draw_nodes_ids(std::span<const uint32_t> node_ids);
  // Draws the BLEND items deferred since begin_frame(..., defer_blended = true), back to front
  // (the order above). Returns what it drew; nothing without deferred items.
  DrawStats end_frame();

  // Where a draw goes in one draw call's order of opaque and MASK draws: by batch key, then
  // segment, then the squared distance from the eye to its object's box centre (then the order
  // collected, which the caller knows).
  struct DrawOrder {
    uint64_t key = 0;
    uint32_t segment = 0;
    double distance2 = 0;
    auto operator<=>(const DrawOrder&) const = default;
  };
  // The DrawOrder of each opaque and MASK Shaded draw of renderable `id` in this frame
  // (begin_frame's eye), in the order draw_renderables collects them, into `out` (cleared).
  // Draws nothing. Throws std::out_of_range for an id not in r.
  void draw_order(const Renderables& r, uint32_t id, std::vector<DrawOrder>& out);

  // Occlusion queries (scene_renderer_queries.cpp).
  // One GL_SAMPLES_PASSED query around the DepthOnly draws of renderables `ids` — the same
  // programs, vertices, face culling and MASK alpha test as draw_renderables(..., DepthOnly), so
  // their depth is bit-identical to the occluder pass's — with colour and depth writes off, depth
  // test depth_func and no occluder offset. BLEND items are left out, as in DepthOnly. With
  // GL_EQUAL the query counts the samples that tie with the depth buffer exactly (every mode
  // computes the same depth: a Shaded draw would tie there too): TwoPassDrawer's tie check.
  // Leaves depth writes on and the depth test GL_GREATER. Throws std::out_of_range for an id not in r.
  void query_renderables(const Renderables& r, std::span<const uint32_t> ids, GLuint query, GLenum depth_func);
  // The BLEND items' share of an exact visibility count: for each BLEND item items[k] (others
  // are an error), a GL_SAMPLES_PASSED query queries[k] around a depth-tested draw of it against
  // the depth buffer as it is (GL_GREATER, no colour or depth writes: what the Shaded pass does to
  // glass after the opaque draws). A non-zero count means the item shows in the frame; the item
  // buffer (ItemIds) leaves BLEND items out. Leaves depth writes on.
  void query_blended_items(std::span<const uint32_t> items, std::span<const GLuint> queries);
  // True when item `item` has a BLEND material.
  bool item_blended(uint32_t item) const;

  // The scene's shader variants, e.g. "shaded: plain, blended; depth: plain; ids: plain".
  const std::string& variants() const { return gpu_.variants; }
  // Streaming (SceneUpload::budget_bytes): the pool, with what streaming has cost; else null.
  const GeometryPool* geometry_pool() const { return gpu_.pool.get(); }
  bool has_blended() const { return gpu_.has_blended; }

 private:
  using ItemDraw = SceneGpu::ItemDraw;
  using ObjectMatrices = SceneGpu::ObjectMatrices;
  using DrawRecord = SceneGpu::DrawRecord;
  struct IndirectCommand {
    uint32_t count, instance_count, first_index;
    int32_t base_vertex;
    uint32_t base_instance;
  };
  struct Pending {  // a collected draw
    uint64_t key;   // batch key (variant bits << 40 | texture + 1 << 8 | culling)
    ItemDraw draw;
    uint32_t id_plus_one;
  };
  struct RunState {  // GL state bound by draw_runs
    unsigned bits = ~0u;
    int64_t texture = -1;
    int cull = -1;
    uint32_t segment = ~0u;
  };
  struct BatchOrder {  // submit(): the order draws are drawn in
    DrawOrder order;
    uint32_t index;  // into pending_
  };

  void begin(const Camera& cam, const float clear_rgba[4]);
  void check_items(std::span<const uint32_t> item_indices) const;
  void check_nodes(std::span<const uint32_t> node_ids) const;
  void check_renderable(const Renderables& r, uint32_t id) const;
  void add_item(uint32_t item, uint32_t id_plus_one, Mode mode, DrawStats& stats);
  // lod: a leaf LOD draw (no texture coordinates, no vertex colours).
  void add_draw(const ItemDraw& d, uint32_t id_plus_one, Mode mode, bool lod, DrawStats& stats);
  uint64_t batch_key(uint32_t object, Mode mode, bool lod) const;
  DrawOrder order_of(const Pending& p) const;
  const ObjectMatrices& object_matrices(uint32_t object);
  void add_renderable(const Renderables& r, uint32_t id, Mode mode, DrawStats& stats);
  DrawStats submit(Mode mode, DrawStats stats);
  DrawStats draw_blended();
  // Uploads `draws` as records and commands and draws them in runs of equal key.
  void draw_batches(std::span<const Pending> draws, Mode mode, bool blended);
  void upload_draws(std::span<const Pending> draws);  // draw i = record i = command i
  // Draws uploaded draws [first, last) in runs of equal key and segment.
  void draw_runs(std::span<const Pending> draws, size_t first, size_t last, Mode mode, RunState& bound);
  // draw_runs over [first, last); streaming, in windows whose pieces are resident together
  // (GeometryPool), each window's draws uploaded before it is drawn. Same order either way.
  void draw_range(std::span<const Pending> draws, size_t first, size_t last, Mode mode, RunState& bound);
  // Binds what draws of batch key `key` in segment `segment` need, where `bound` differs.
  void bind_run(uint64_t key, uint32_t segment, Mode mode, RunState& bound);
  // Uploaded draws [first, last) in indirect calls cut where the flush schedule says.
  void draw_parts(std::span<const Pending> draws, size_t first, size_t last);
  // Face culling back to the default (off, counter-clockwise fronts) after runs left `bound`.
  void reset_cull(const RunState& bound);
  // pending_'s depth-only draws, query k around [query_ends_[k-1], query_ends_[k]), colour and
  // depth writes off, depth test depth_func; leaves depth writes on and the test GL_GREATER.
  void query_pending(std::span<const GLuint> queries, GLenum depth_func);

  const GlApi& gl_;
  const Hierarchy& hierarchy_;
  SceneGpu gpu_;  // what is on the GPU, constant after construction
  bool occluder_offset_ = false;
  FlushSchedule flush_;
  uint32_t pool_generation_ = 0;  // streaming: the arena buffer the vertex array has bound

  // Per-draw buffers: they keep their storage between frames (they grow, never shrink).
  GLuint record_buf_ = 0, indirect_buf_ = 0;
  size_t record_capacity_ = 0, indirect_capacity_ = 0;  // bytes
  std::vector<IndirectCommand> commands_;
  std::vector<DrawRecord> records_;

  // Current frame.
  glm::dmat4 view_rotation_{1.0};
  glm::dvec3 eye_{0.0};
  uint32_t frame_ = 0;
  bool defer_blended_ = false;
  std::vector<uint32_t> object_frame_;           // per object: frame its matrices are from
  std::vector<ObjectMatrices> object_matrices_;  // per object
  std::vector<Pending> pending_;                 // this draw call's draws
  std::vector<Pending> blended_;                 // BLEND draws not drawn yet
  std::vector<Pending> sorted_;
  std::vector<BatchOrder> batch_order_;
  std::vector<std::pair<double, uint32_t>> blend_order_;
  std::vector<size_t> query_ends_;  // query_pending: end of each query's draws
};

// Distinct ids in an item buffer (pixel value - 1, zero pixels ignored), ascending.
std::vector<uint32_t> ids_in_image(const Image& img);

}  // namespace occ
