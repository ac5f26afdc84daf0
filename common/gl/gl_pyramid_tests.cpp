#include "common/gl/gl_pyramid_tests.hpp"

#include <string>

namespace occ {

GpuPyramidTests::GpuPyramidTests(GlContext& ctx) : GpuPyramidTests(ctx, Policy{}) {}

GpuPyramidTests::GpuPyramidTests(GlContext& ctx, const Policy& policy)
    : ctx_(ctx), policy_(policy), queries_(ctx), pyramid_(ctx) {}

void GpuPyramidTests::begin(const Camera& cam) {
  cam_ = cam;
  built_ = stale_ = false;
  queries_.begin(cam);
}

void GpuPyramidTests::depth_added(std::span<const Aabb>) {
  stale_ = built_;
  queries_.begin(cam_);
}

uint32_t GpuPyramidTests::issue(const Aabb& box) {
  ++stats_.tests;
  return batch_.add(box, false, cam_, {ctx_.width(), ctx_.height()}, policy_.span);
}

uint32_t GpuPyramidTests::issue_cheap(const Aabb& box) {
  ++stats_.tests;
  ++stats_.cheap;
  return batch_.add(box, true, cam_, {ctx_.width(), ctx_.height()}, policy_.span);
}

void GpuPyramidTests::resolve() {
  batch_.resolve_start();
  if (!batch_.sent.empty()) {
    if (!built_ || (stale_ && batch_.sent.size() >= policy_.rebuild_min_probes)) {
      pyramid_.build();
      built_ = true;
      stale_ = false;
      ++stats_.builds;
    }
    pyramid_.test(batch_.sent, batch_.occluded);
    ++stats_.dispatches;
    stats_.pyramid_tested += batch_.sent.size();
    uint64_t pixels = 0;
    stats_.pyramid_occluded += batch_.take_occluded(pixels);
    queries_.begin(cam_);  // the dispatches changed the program
  }
  stats_.assumed += batch_.assume_cheap();
  for (size_t i = 0; i < batch_.boxes.size(); ++i)
    if (batch_.answer[i] == PyramidBatch::kPending) {
      batch_.answer[i] = queries_.issue(batch_.boxes[i]);
      ++stats_.queries;
    }
}

uint64_t GpuPyramidTests::result(uint32_t handle) {
  if (!batch_.resolved) resolve();
  const uint32_t a = batch_.at(handle);
  const uint64_t samples = a == PyramidBatch::kZero ? 0 : a == PyramidBatch::kAssumed ? 1 : queries_.result(a);
  stats_.occluded += samples == 0;
  return samples;
}

void GpuPyramidTests::end_batch() {
  queries_.reset();
  batch_.clear();
}

OcclusionCounts GpuPyramidTests::counts() const {
  const Stats& q = stats_;
  const auto n = [](uint64_t v) { return std::to_string(v); };
  OcclusionCounts c;
  c.boxes_tested = q.tests;
  c.boxes_occluded = q.occluded;
  c.more.push_back(n(q.queries) + " occlusion queries issued");
  c.more.push_back(n(q.pyramid_occluded) + " proven occluded by the depth pyramid of " + n(q.pyramid_tested) +
                   " tested against it in " + n(q.dispatches) + " dispatches, " + n(q.builds) + " pyramid builds");
  if (q.cheap) c.more.push_back(n(q.assumed) + " of " + n(q.cheap) + " skipped by adaptive queries assumed visible");
  return c;
}

}  // namespace occ
