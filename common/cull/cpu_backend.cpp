#include "common/cull/cpu_backend.hpp"

#include <algorithm>

namespace occ {

CpuBackend::CpuBackend(CpuOccluders& occluders, const Renderables& r, bool leaf_tests)
    : OcclusionBackend(r.count()), occ_(occluders), r_(r), leaf_tests_(leaf_tests), tests_(occluders) {
  if (leaf_tests_) seen_.assign(r_.hierarchy().size(), 0);
}

void CpuBackend::restart() { std::fill(seen_.begin(), seen_.end(), 0); }

void CpuBackend::draw_depth(std::span<const uint32_t> fresh) {
  for (uint32_t id : fresh) occ_.draw_leaf(r_.node_of(id), r_.level_of(id));
}

void CpuBackend::start_tests(uint32_t frame, const Camera& cam) {
  frame_ = frame;
  tests_.begin(cam);
}

void CpuBackend::depth_added(std::span<const uint32_t> fresh) {
  boxes_.clear();
  for (uint32_t id : fresh) boxes_.push_back(r_.hierarchy().node(r_.node_of(id)).box);
  tests_.depth_added(boxes_);
}

uint64_t CpuBackend::result(uint32_t handle) {
  const uint64_t samples = tests_.result(handle);
  occluded_ += samples == 0;
  return samples;
}

bool CpuBackend::leaf_may_show(uint32_t leaf) {
  if (!leaf_tests_) return true;
  uint32_t& seen = seen_.at(leaf);
  if (seen != 0 && frame_ + 1 < seen + kRecheck) return true;
  ++leaves_tested_;
  if (!occ_.leaf_shows(leaf)) {
    ++leaves_hidden_;
    return false;
  }
  seen = frame_ + 1;
  return true;
}

OcclusionCounts CpuBackend::counts() const {
  OcclusionCounts c;
  c.boxes_tested = tests_.stats().tests;
  c.boxes_occluded = occluded_;
  c.more.push_back(std::to_string(tests_.stats().pyramid_occluded) + " proven occluded by the depth pyramid, " +
                   std::to_string(tests_.stats().raster_occluded) + " by their faces");
  if (leaf_tests_)
    c.more.push_back(std::to_string(leaves_tested_) + " leaves tested by their triangles (" +
                     std::to_string(leaves_hidden_) + " hidden)");
  return c;
}

}  // namespace occ
