#include "common/gl/geometry_query.hpp"

#include <algorithm>
#include <span>
#include <stdexcept>
#include <string>

namespace occ {

GeometryQuerier::GeometryQuerier(GlContext& ctx, OcclusionQueries& boxes, SceneRenderer& renderer,
                                 const Renderables& r, std::function<void()> restore)
    : gl_(ctx.gl()), boxes_(boxes), renderer_(renderer), r_(r), restore_(std::move(restore)) {}

GeometryQuerier::~GeometryQuerier() {
  if (!pool_.empty()) gl_.DeleteQueries(GLsizei(pool_.size()), pool_.data());
}

uint32_t GeometryQuerier::issue_geometry(uint32_t renderable) {
  if (renderer_.holds_blended(r_, renderable)) return kNoGeometryQuery;
  if (ids_.size() >= kGeometryBit) throw std::length_error("GeometryQuerier: too many geometry queries in one batch");
  ids_.push_back(renderable);
  ++issued_;
  return kGeometryBit | uint32_t(ids_.size() - 1);
}

void GeometryQuerier::flush() {
  if (drawn_ == ids_.size()) return;
  if (pool_.size() < ids_.size()) {
    const size_t old = pool_.size(), grown = std::max(ids_.size(), old + 64);
    pool_.resize(grown);
    gl_.CreateQueries(GL_SAMPLES_PASSED, GLsizei(grown - old), pool_.data() + old);
  }
  const std::span<const uint32_t> ids(ids_.data() + drawn_, ids_.size() - drawn_);
  renderer_.query_renderables(r_, ids, std::span<const GLuint>(pool_.data() + drawn_, ids.size()));
  drawn_ = ids_.size();
  if (restore_) restore_();
}

uint64_t GeometryQuerier::result(uint32_t handle) {
  if (!(handle & kGeometryBit)) return boxes_.result(handle);
  const uint32_t k = handle & ~kGeometryBit;
  if (k >= ids_.size())
    throw std::out_of_range("GeometryQuerier: geometry query handle " + std::to_string(k) +
                            " not issued in this batch (" + std::to_string(ids_.size()) + " issued)");
  flush();
  GLuint64 samples = 0;
  gl_.GetQueryObjectui64v(pool_[k], GL_QUERY_RESULT, &samples);
  return samples;
}

void GeometryQuerier::end_batch() {
  boxes_.end_batch();
  ids_.clear();
  drawn_ = 0;
}

}  // namespace occ
