// SceneRenderer's occlusion queries around its own draws (scene_renderer.hpp, "Occlusion
// queries"): query_renderables (TwoPassDrawer's tie check), query_blended_items (the reference's
// exact BLEND counts), and what they ask of the scene's materials.
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

void SceneRenderer::query_renderables(const Renderables& r, std::span<const uint32_t> ids, GLuint query,
                                      GLenum depth_func) {
  if (ids.empty()) return;
  // The renderables' depth-only draws (BLEND items left out, as DepthOnly does), in batch-key order.
  pending_.clear();
  query_ends_.clear();
  DrawStats unused;
  for (uint32_t id : ids) {
    check_renderable(r, id);
    add_renderable(r, id, Mode::DepthOnly, unused);
  }
  std::stable_sort(pending_.begin(), pending_.end(), [](const Pending& a, const Pending& b) { return a.key < b.key; });
  query_ends_.push_back(pending_.size());
  // The occluders' state without their offset, depth writes off, the caller's depth test.
  query_pending(std::span<const GLuint>(&query, 1), depth_func);
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
  if (!gpu_.pool) upload_draws(pending_);  // streaming: per window (draw_range)
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
    draw_range(pending_, b, query_ends_[k], Mode::DepthOnly, bound);
    gl_.EndQuery(GL_SAMPLES_PASSED);
    b = query_ends_[k];
  }
  pending_.clear();
  reset_cull(bound);
  gl_.DepthFunc(GL_GREATER);
  gl_.DepthMask(GL_TRUE);
}

}  // namespace occ
