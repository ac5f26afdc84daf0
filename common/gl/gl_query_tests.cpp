#include "common/gl/gl_query_tests.hpp"

#include <string>

namespace occ {

void QueryTests::begin(const Camera& cam) {
  cam_ = cam;
  queries_.begin(cam);
}

uint32_t QueryTests::issue(const Aabb& box) {
  ++tests_;
  return queries_.issue(box);
}

uint64_t QueryTests::result(uint32_t handle) {
  const uint64_t samples = queries_.result(handle);
  occluded_ += samples == 0;
  return samples;
}

OcclusionCounts QueryTests::counts() const {
  return {.boxes_tested = tests_, .boxes_occluded = occluded_, .more = {std::to_string(tests_) + " occlusion queries issued"}};
}

}  // namespace occ
