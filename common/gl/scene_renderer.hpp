// Draws the items of a Scene/Hierarchy (object x mesh cluster) in one of three modes:
//   Shaded     headlight Lambert (light at the eye, |n.l| so back faces of open CAD meshes read
//              well) on a mild per-object base colour derived from a hash of the object index;
//   DepthOnly  colour writes off, depth writes on, the cheapest shader (occluder rendering);
//   ItemIds    colour = id + 1 as a little-endian 32-bit RGBA8 value (item index, or node id with
//              draw_nodes_ids), 0 = nothing: an item buffer for exact visibility (ids_in_image).
// Every mode computes gl_Position with the same invariant expression, so depth written by one
// mode is matched exactly by another.
//
// GPU layout (uploaded once at construction):
//   vertex buffer  all meshes back to back, interleaved {vec3 position; vec3 normal;} float,
//                  24 bytes (attributes 0 and 1, binding 0); a mesh starts at its base vertex;
//   index buffer   all meshes' u32 triangle lists back to back; item = one cluster range.
// Per draw call (only what is drawn): one DrawElementsIndirectCommand per item (baseVertex = its
// mesh, firstIndex = its cluster, baseInstance = draw slot i) and one DrawRecord per item, read
// as instanced attributes (binding 1, divisor 1, so baseInstance selects record i):
//   locations 2..5  mat4 model_view      view_rotation * (model with its translation - eye),
//                                        computed in double, then rounded to float: camera-
//                                        relative, so scenes 1e7 from the origin do not crack;
//   locations 6..8  vec4 normal_color[3] normal-matrix columns (xyz), base colour (w);
//   location 9      uint id + 1.
// An object's matrices are computed once per frame and reused by all its items.
//
// Contracts: the GlContext is current on the calling thread for every call; the context and the
// hierarchy outlive the renderer; `scene` is the one the hierarchy was built from (its clusters)
// and is only read in the constructor (meshes go to the GPU, transforms are copied). Invalid item or node ids throw
// std::out_of_range. Faces are never culled.
#pragma once
#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include <glm/glm.hpp>

#include "common/camera.hpp"
#include "common/gl/context.hpp"
#include "common/hierarchy.hpp"
#include "common/image.hpp"
#include "common/lod.hpp"
#include "common/scene.hpp"

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
  enum class Mode { Shaded, DepthOnly, ItemIds };
  static constexpr std::array<uint8_t, 4> kBackgroundRgba8{20, 23, 28, 255};
  // With set_occluder_offset(true), DepthOnly draws use glPolygonOffset(-this, -this).
  static constexpr float kOccluderSlopeOffset = 0.1f;

  // With `lod`, its leaf LODs and HLODs are uploaded too (draw_renderables); it must outlive
  // nothing (only read here).
  SceneRenderer(GlContext& ctx, const Scene& scene, const Hierarchy& hierarchy, const LodData* lod = nullptr);
  ~SceneRenderer();
  SceneRenderer(const SceneRenderer&) = delete;
  SceneRenderer& operator=(const SceneRenderer&) = delete;

  // Occluders for a later query pass of the same depth buffer (the switch's and the occlusion
  // server's OR): DepthOnly draws go a tenth of a pixel's depth slope farther back (reverse-Z:
  // glPolygonOffset(-0.1, -0.1), switched off again after each draw). llvmpipe rasterises a
  // sliver seen almost edge-on at depths up to ~1e-4 (relative) in front of its own vertices,
  // beyond the query box's 1e-5 padding, so an occluder could hide its own box from the next HC
  // although brute force shows it (issue 13: 16 pixels in frame 108 of the duplex layout walk,
  // 16 in the 2.6 M city walk). Off by default: a renderer that queries each node before drawing
  // it (CHC, stop-and-wait) does not need it, and toggling the state per draw costs llvmpipe.
  void set_occluder_offset(bool on) { occluder_offset_ = on; }

  // Starts a frame for `cam`: clears depth to 0 (far) and, if clear_color, colour to
  // kBackgroundRgba8; forgets the previous frame's per-object transforms.
  void begin_frame(const Camera& cam, bool clear_color);
  // begin_frame for an item buffer: colour cleared to 0 (= no id).
  void begin_id_frame(const Camera& cam);

  // Draws the given items (indices into hierarchy.items()) in this order; ItemIds writes
  // item index + 1. Returns {items, triangles} drawn.
  DrawStats draw_items(std::span<const uint32_t> item_indices, Mode mode);
  // All items of each node's contiguous range [first_item, first_item + item_count).
  DrawStats draw_nodes(std::span<const uint32_t> node_ids, Mode mode);
  // Renderable ids (lod.hpp): leaves at level 0 draw their items, leaves at level l their items'
  // level-l LODs with the objects' transforms and colours, interior nodes their HLOD (per-vertex
  // colours of the source objects). Draw order: by the node's first item, then level — for
  // level-0 leaves exactly ascending item order, as everywhere else (z-ties resolve identically).
  // Without LOD data uploaded, LOD ids fall back to full detail.
  DrawStats draw_renderables(const Renderables& r, std::span<const uint32_t> ids, Mode mode);
  // ItemIds rendering of whole nodes, each in colour node id + 1.
  DrawStats draw_nodes_ids(std::span<const uint32_t> node_ids);

 private:
  bool occluder_offset_ = false;
  struct ItemDraw {
    uint32_t index_count, first_index;
    int32_t base_vertex;
    uint32_t object;
  };
  struct ObjectMatrices {  // an object's per-frame data, as laid out in DrawRecord
    glm::mat4 model_view;
    glm::vec4 normal_color[3];
  };
  struct DrawRecord {
    ObjectMatrices object;
    uint32_t id_plus_one;
  };
  struct IndirectCommand {
    uint32_t count, instance_count, first_index;
    int32_t base_vertex;
    uint32_t base_instance;
  };

  void begin(const Camera& cam, const float clear_rgba[4]);
  void check_items(std::span<const uint32_t> item_indices) const;
  void check_nodes(std::span<const uint32_t> node_ids) const;
  void add_item(uint32_t item, uint32_t id_plus_one, DrawStats& stats);
  void add_draw(const ItemDraw& d, uint32_t id_plus_one, DrawStats& stats);
  const ObjectMatrices& object_matrices(uint32_t object);
  DrawStats submit(Mode mode, DrawStats stats);

  const GlApi& gl_;
  const Hierarchy& hierarchy_;
  std::vector<glm::dmat4> transforms_;  // per object
  std::vector<ItemDraw> item_draws_;    // per hierarchy item
  std::vector<ItemDraw> lod_draws_;     // per LodData cluster LOD (object filled per draw)
  std::vector<ItemDraw> hlod_draws_;    // per HLOD (object = a pseudo-object: its origin)
  std::vector<uint32_t> item_slot_;     // per item: LodData slot
  std::vector<uint32_t> hlod_of_node_;  // per node: HLOD index or kNoNode
  GLuint programs_[3] = {};             // indexed by Mode
  GLint projection_loc_[3] = {};
  GLuint vao_ = 0, vertex_buf_ = 0, index_buf_ = 0, record_buf_ = 0, indirect_buf_ = 0;

  // Current frame.
  glm::dmat4 view_rotation_{1.0};
  glm::dvec3 eye_{0.0};
  uint32_t frame_ = 0;
  std::vector<uint32_t> object_frame_;         // per object: frame its matrices are from
  std::vector<ObjectMatrices> object_matrices_;  // per object
  std::vector<IndirectCommand> commands_;
  std::vector<DrawRecord> records_;
};

// Distinct ids in an item buffer (pixel value - 1, zero pixels ignored), ascending.
std::vector<uint32_t> ids_in_image(const Image& img);

}  // namespace occ
