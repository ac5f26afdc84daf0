#include "common/gl/scene_renderer.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>
#include <tuple>

#include <glm/gtc/type_ptr.hpp>

namespace occ {

using namespace gl_detail;

namespace {

constexpr uint64_t kBlendKey = uint64_t(1) << 63;

// A batch key: variant bits (of the mode drawn), texture + 1 (0: untextured), face culling.
uint64_t pack_key(unsigned bits, const SceneGpu::ObjectLook& look) {
  const uint64_t texture = (bits & kTextured) ? uint64_t(look.texture) + 1 : 0;
  return uint64_t(bits) << 40 | texture << 8 | look.cull;
}

}  // namespace

// Without Upload::release nothing is written through these pointers.
SceneRenderer::SceneRenderer(GlContext& ctx, const Scene& scene, const Hierarchy& hierarchy, const LodData* lod)
    : SceneRenderer(ctx, const_cast<Scene&>(scene), hierarchy, const_cast<LodData*>(lod), Upload{}) {}

SceneRenderer::SceneRenderer(GlContext& ctx, Scene& scene, const Hierarchy& hierarchy, LodData* lod,
                             const Upload& upload)
    : gl_(ctx.gl()),
      hierarchy_(hierarchy),
      gpu_(ctx.gl(), scene, hierarchy, lod, upload),
      flush_() {
  static_assert(sizeof(IndirectCommand) == 20);
  if (gpu_.pool) pool_generation_ = gpu_.pool->generation();  // bound by SceneGpu
  object_frame_.assign(gpu_.transforms.size(), 0);
  object_matrices_.resize(gpu_.transforms.size());
}

SceneRenderer::~SceneRenderer() {
  const GLuint buffers[] = {record_buf_, indirect_buf_};
  for (GLuint b : buffers)
    if (b) gl_.DeleteBuffers(1, &b);
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
  // Section planes in view space: n.x + d at x = eye + R^T p is (R n).p + (n.eye + d), in double.
  glm::vec4 sections[Sections::kMax];
  for (int i = 0; i < Sections::kMax; ++i) {
    if (i >= cam.sections.count) {
      sections[i] = glm::vec4(0, 0, 0, 1);  // keeps everything (and is disabled)
      continue;
    }
    const Plane& pl = cam.sections.planes[size_t(i)];
    sections[i] = glm::vec4(glm::vec3(glm::dmat3(view_rotation_) * pl.n), float(pl.distance(cam.eye)));
  }
  for (auto& mode : gpu_.programs)
    for (const SceneGpu::Program& p : mode)
      if (p.id) {
        gl_.ProgramUniformMatrix4fv(p.id, p.projection_loc, 1, GL_FALSE, glm::value_ptr(projection));
        if (p.sections_loc >= 0) gl_.ProgramUniform4fv(p.id, p.sections_loc, Sections::kMax, glm::value_ptr(sections[0]));
      }
  for (int i = 0; i < Sections::kMax; ++i) {
    if (i < cam.sections.count)
      gl_.Enable(GLenum(GL_CLIP_DISTANCE0 + i));
    else
      gl_.Disable(GLenum(GL_CLIP_DISTANCE0 + i));
  }
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
  glm::dmat4 relative = gpu_.transforms[object];
  relative[3] -= glm::dvec4(eye_, 0.0);  // translate by -eye in double, before rounding
  const glm::dmat4 model_view = view_rotation_ * relative;
  // inverse transpose of (rotation x model) = rotation x inverse transpose of model
  const glm::dmat3 normal_matrix = glm::dmat3(view_rotation_) * gpu_.normal_world[object];
  const SceneGpu::ObjectLook& look = gpu_.looks[object];
  m.model_view = glm::mat4(model_view);
  for (int c = 0; c < 3; ++c) m.normal_color[c] = glm::vec4(glm::vec3(normal_matrix[c]), look.color[c]);
  m.alpha_cutoff = {look.color.a, look.cutoff};
  return m;
}

void SceneRenderer::check_items(std::span<const uint32_t> item_indices) const {
  for (uint32_t item : item_indices)
    if (item >= gpu_.item_draws.size())
      throw std::out_of_range("SceneRenderer: item " + std::to_string(item) + " out of range (" +
                              std::to_string(gpu_.item_draws.size()) + " items)");
}

void SceneRenderer::check_nodes(std::span<const uint32_t> node_ids) const {
  for (uint32_t id : node_ids)
    if (id >= hierarchy_.size())
      throw std::out_of_range("SceneRenderer: node " + std::to_string(id) + " out of range (" +
                              std::to_string(hierarchy_.size()) + " nodes)");
}

void SceneRenderer::check_renderable(const Renderables& r, uint32_t id) const {
  if (id >= r.count())
    throw std::out_of_range("SceneRenderer: renderable " + std::to_string(id) + " out of range (" +
                            std::to_string(r.count()) + ")");
}

// Batch key of an object's draws in `mode`; kBlendKey marks BLEND draws.
uint64_t SceneRenderer::batch_key(uint32_t object, Mode mode, bool lod) const {
  const SceneGpu::ObjectLook& look = gpu_.looks[object];
  const unsigned bits = lod ? lod_bits(look.bits) : look.bits;
  if (bits & kBlend) return kBlendKey;
  return pack_key(mode_bits(mode, bits), look);
}

SceneRenderer::DrawOrder SceneRenderer::order_of(const Pending& p) const {
  const glm::dvec3 d = gpu_.centers[p.draw.object] - eye_;
  return {p.key, p.draw.segment, glm::dot(d, d)};
}

void SceneRenderer::add_item(uint32_t item, uint32_t id_plus_one, Mode mode, DrawStats& stats) {
  add_draw(gpu_.item_draws[item], id_plus_one, mode, false, stats);
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

void SceneRenderer::draw_order(const Renderables& r, uint32_t id, std::vector<DrawOrder>& out) {
  check_renderable(r, id);
  // Collected as draw_renderables collects it, then taken back out.
  const size_t pending = pending_.size(), blended = blended_.size();
  DrawStats unused;
  add_renderable(r, id, Mode::Shaded, unused);
  out.clear();
  for (size_t i = pending; i < pending_.size(); ++i) out.push_back(order_of(pending_[i]));
  pending_.resize(pending);
  blended_.resize(blended);
}

DrawStats SceneRenderer::draw_renderables(const Renderables& r, std::span<const uint32_t> ids, Mode mode) {
  std::vector<std::pair<uint64_t, uint32_t>> order;  // (first item << 8 | level, id)
  order.reserve(ids.size());
  for (uint32_t id : ids) {
    check_renderable(r, id);
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
  if (n.leaf() && level > 0 && !gpu_.lod_draws.empty()) {
    for (uint32_t i = n.first_item; i < n.first_item + n.item_count; ++i) {
      ItemDraw d = gpu_.lod_draws[gpu_.item_slot[i] * kLeafLodLevels + level - 1];
      d.object = gpu_.item_draws[i].object;
      add_draw(d, i + 1, mode, true, stats);
    }
  } else if (!n.leaf() && !gpu_.hlod_draws.empty() && gpu_.hlod_of_node[node] != kNoNode) {
    // ItemIds: an HLOD writes items + node + 1, apart from every item id.
    const uint32_t id_plus_one = (mode == Mode::ItemIds ? uint32_t(hierarchy_.items().size()) : 0u) + node + 1;
    add_draw(gpu_.hlod_draws[gpu_.hlod_of_node[node]], id_plus_one, mode, false, stats);  // its look: vertex colours
  } else {
    for (uint32_t i = n.first_item; i < n.first_item + n.item_count; ++i) add_item(i, i + 1, mode, stats);
  }
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
    // buffer first, so llvmpipe skips shading the fragments they hide. The order of any two
    // draws depends only on them and the camera, so every renderer (reference, RVG, any subset
    // of the scene) resolves depth ties between them alike.
    batch_order_.clear();
    for (uint32_t i = 0; i < pending_.size(); ++i) batch_order_.push_back({order_of(pending_[i]), i});
    std::sort(batch_order_.begin(), batch_order_.end(), [](const BatchOrder& a, const BatchOrder& b) {
      return std::tie(a.order, a.index) < std::tie(b.order, b.index);
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
    const glm::dvec3 d = gpu_.centers[blended_[i].draw.object] - eye_;
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
    const SceneGpu::ObjectLook& look = gpu_.looks[p.draw.object];
    p.key = pack_key(mode_bits(Mode::Shaded, p.key ? lod_bits(look.bits) : look.bits), look);
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
  const GeometryPool* pool = gpu_.pool.get();
  for (const Pending& p : draws) {
    records_.push_back({object_matrices(p.draw.object), p.id_plus_one});
    uint32_t first = p.draw.first_index;
    int32_t base = p.draw.base_vertex;
    if (pool) first += pool->first_index(p.draw.piece), base += pool->base_vertex(p.draw.piece);
    commands_.push_back({p.draw.index_count, 1, first, base, uint32_t(commands_.size())});
  }
  // Buffers keep their storage between calls; they only grow (never a per-frame allocation).
  const size_t record_bytes = records_.size() * sizeof(DrawRecord);
  const size_t command_bytes = commands_.size() * sizeof(IndirectCommand);
  if (record_bytes > record_capacity_) {
    if (record_buf_) gl_.DeleteBuffers(1, &record_buf_);
    record_capacity_ = std::max(record_bytes + record_bytes / 2, size_t(64) << 10);
    gl_.CreateBuffers(1, &record_buf_);
    gl_.NamedBufferStorage(record_buf_, GLsizeiptr(record_capacity_), nullptr, GL_DYNAMIC_STORAGE_BIT);
    gl_.VertexArrayVertexBuffer(gpu_.vao, 1, record_buf_, 0, sizeof(DrawRecord));
  }
  if (command_bytes > indirect_capacity_) {
    if (indirect_buf_) gl_.DeleteBuffers(1, &indirect_buf_);
    indirect_capacity_ = std::max(command_bytes + command_bytes / 2, size_t(16) << 10);
    gl_.CreateBuffers(1, &indirect_buf_);
    gl_.NamedBufferStorage(indirect_buf_, GLsizeiptr(indirect_capacity_), nullptr, GL_DYNAMIC_STORAGE_BIT);
    gl_.BindBuffer(GL_DRAW_INDIRECT_BUFFER, indirect_buf_);  // streaming uploads between a call's windows
  }
  gl_.NamedBufferSubData(record_buf_, 0, GLsizeiptr(record_bytes), records_.data());
  gl_.NamedBufferSubData(indirect_buf_, 0, GLsizeiptr(command_bytes), commands_.data());
}

void SceneRenderer::draw_runs(std::span<const Pending> draws, size_t first, size_t last, Mode mode, RunState& bound) {
  for (size_t b = first; b < last;) {
    size_t e = b + 1;
    const uint32_t segment = draws[b].draw.segment;
    while (e < last && draws[e].key == draws[b].key && draws[e].draw.segment == segment) ++e;
    bind_run(draws[b].key, segment, mode, bound);
    draw_parts(draws, b, e);
    b = e;
  }
}

void SceneRenderer::draw_range(std::span<const Pending> draws, size_t first, size_t last, Mode mode,
                               RunState& bound) {
  if (!gpu_.pool) {
    draw_runs(draws, first, last, mode, bound);
    return;
  }
  GeometryPool& pool = *gpu_.pool;
  for (size_t b = first; b < last;) {
    pool.begin_window();
    size_t e = b;
    while (e < last && pool.acquire(draws[e].draw.piece)) ++e;  // e > b: a fresh window fits one
    if (e < last) pool.count_extra_window();
    if (pool.generation() != pool_generation_) {  // the arena grew into a new buffer
      gpu_.bind_segment(0);
      pool_generation_ = pool.generation();
    }
    upload_draws(draws.subspan(b, e - b));
    draw_runs(draws.subspan(b, e - b), 0, e - b, mode, bound);
    b = e;
  }
}

void SceneRenderer::bind_run(uint64_t key, uint32_t segment, Mode mode, RunState& bound) {
  segment = gpu_.physical_segment(segment);
  if (segment != bound.segment) {
    gpu_.bind_segment(segment);
    bound.segment = segment;
  }
  const unsigned bits = unsigned(key >> 40) & (kVariants - 1);
  const int64_t texture = int64_t((key >> 8) & 0xffffffffu) - 1;
  const int cull = int(key & 0xff);
  if (bits != bound.bits) {
    gl_.UseProgram(gpu_.program(mode, bits).id);
    bound.bits = bits;
  }
  if (texture >= 0 && texture != bound.texture) {
    gpu_.bind_texture(size_t(texture));
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
}

// One indirect call per part of the flush schedule, a glFlush after each full part.
void SceneRenderer::draw_parts(std::span<const Pending> draws, size_t first, size_t last) {
  for (size_t c = first; c < last;) {
    size_t d = c;
    uint64_t triangles = 0;
    do {
      triangles += draws[d++].draw.index_count / 3;
    } while (d < last && flush_.fits(triangles));
    gl_.MultiDrawElementsIndirect(GL_TRIANGLES, GL_UNSIGNED_INT,
                                  reinterpret_cast<const void*>(c * sizeof(IndirectCommand)), GLsizei(d - c), 0);
    if (flush_.submitted(triangles)) gl_.Flush();
    c = d;
  }
}

void SceneRenderer::reset_cull(const RunState& bound) {
  if (bound.cull != kCullNone) {
    gl_.Disable(GL_CULL_FACE);
    gl_.FrontFace(GL_CCW);
  }
}

void SceneRenderer::draw_batches(std::span<const Pending> draws, Mode mode, bool blended) {
  if (!gpu_.pool) upload_draws(draws);  // streaming: per window (draw_range)
  uint64_t triangles = 0;
  for (const Pending& p : draws) triangles += p.draw.index_count / 3;
  flush_.begin_call(triangles);
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
  gl_.BindVertexArray(gpu_.vao);
  gl_.BindBuffer(GL_DRAW_INDIRECT_BUFFER, indirect_buf_);
  RunState bound;
  bound.segment = gpu_.segments.size() > 1 ? ~0u : 0;  // bound at construction
  draw_range(draws, 0, draws.size(), mode, bound);
  // Leave the defaults for other GL users (BoxQuerier, HZB readback).
  if (offset) gl_.Disable(GL_POLYGON_OFFSET_FILL);  // never on query boxes or shaded frames
  reset_cull(bound);
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
