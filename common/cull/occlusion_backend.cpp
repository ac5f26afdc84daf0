#include "common/cull/occlusion_backend.hpp"

#include <algorithm>

namespace occ {

void OcclusionBackend::begin(const Camera& cam) {
  std::fill(drawn_.begin(), drawn_.end(), 0);
  testing_ = false;
  clear_depth(cam);
}

size_t OcclusionBackend::draw(std::span<const uint32_t> ids) {
  fresh_.clear();
  for (uint32_t id : ids)
    if (!drawn_.at(id)) {
      drawn_[id] = 1;
      fresh_.push_back(id);
    }
  if (fresh_.empty()) return 0;
  draw_depth(fresh_);
  if (testing_) depth_added(fresh_);
  return fresh_.size();
}

void OcclusionBackend::occluders_found(std::span<const uint32_t> found) { draw(found); }

}  // namespace occ
