// SceneRenderer's occlusion queries around its own draws (scene_renderer.hpp, "Occlusion
// queries"): query_renderables (TwoPassDrawer's tie check with one query; GeometryQuerier's
// geometry queries with one per renderable), query_blended_items (the reference's exact BLEND
// counts), and what they ask of the scene's materials. holds_blended is GeometryQuerier's only.
#include <algorithm>
#include <stdexcept>
#include <string>

#include "common/gl/scene_renderer.hpp"

namespace occ {

using namespace gl_detail;

bool SceneRenderer::item_blended(uint32_t item) const {
  if (item >= gpu_.item_draws.size())
    throw std::out_of_range("SceneRenderer: item " + std::to_string(item) + " out of range (" +
                            std::to_string(gpu_.item_draws.size()) + ")");
  return (gpu_.looks[gpu_.item_draws[item].object].bits & kBlend) != 0;
}

bool SceneRenderer::holds_blended(const Renderables& r, uint32_t id) const {
  if (!gpu_.has_blended) return false;
  check_renderable(r, id);
  const uint32_t node = r.node_of(id);
  const HNode& n = hierarchy_.node(node);
  if (!n.leaf() && !gpu_.hlod_draws.empty() && gpu_.hlod_of_node[node] != kNoNode) return false;  // HLODs are opaque
  for (uint32_t i = n.first_item; i < n.first_item + n.item_count; ++i)
    if (gpu_.looks[gpu_.item_draws[i].object].bits & kBlend) return true;
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
    check_renderable(r, id);
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
    const ItemDraw& d = gpu_.item_draws[item];
    pending_.push_back({uint64_t(gpu_.looks[d.object].cull), d, item + 1});  // the plain depth program
    query_ends_.push_back(pending_.size());
  }
  query_pending(queries, GL_GREATER);  // as the Shaded pass draws glass: ties fail
}

void SceneRenderer::query_pending(std::span<const GLuint> queries, GLenum depth_func) {
  upload_draws(pending_);
  flush_.begin_queries();
  gl_.ColorMask(GL_FALSE, GL_FALSE, GL_FALSE, GL_FALSE);
  gl_.DepthMask(GL_FALSE);
  gl_.Enable(GL_DEPTH_TEST);
  gl_.DepthFunc(depth_func);
  gl_.BindVertexArray(gpu_.vao);
  gl_.BindBuffer(GL_DRAW_INDIRECT_BUFFER, indirect_buf_);
  RunState bound;
  bound.segment = gpu_.segments.size() > 1 ? ~0u : 0;
  size_t b = 0;
  for (size_t k = 0; k < queries.size(); ++k) {
    gl_.BeginQuery(GL_SAMPLES_PASSED, queries[k]);
    draw_runs(pending_, b, query_ends_[k], Mode::DepthOnly, bound);
    gl_.EndQuery(GL_SAMPLES_PASSED);
    b = query_ends_[k];
  }
  pending_.clear();
  reset_cull(bound);
  gl_.DepthFunc(GL_GREATER);
  gl_.DepthMask(GL_TRUE);
}

}  // namespace occ
