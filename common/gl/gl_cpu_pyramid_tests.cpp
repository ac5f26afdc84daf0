#include "common/gl/gl_cpu_pyramid_tests.hpp"

#include <cstdio>
#include <stdexcept>
#include <string>

namespace occ {

CpuPyramidTests::CpuPyramidTests(GlContext& ctx, bool sample_counts)
    : CpuPyramidTests(ctx, sample_counts, Policy{}) {}

CpuPyramidTests::CpuPyramidTests(GlContext& ctx, bool sample_counts, const Policy& policy)
    : ctx_(ctx), sample_counts_(sample_counts), policy_(policy), queries_(ctx), counter_(ctx, sample_counts) {}

void CpuPyramidTests::begin(const Camera& cam) {
  // The frame just ended decided boxes covering that many pixels; frames whose pyramid would not
  // pay do without it, with a frame with the pyramid every kRetryFrames to look again.
  if (built_) proven_avg_ = proven_avg_ < 0 ? double(proven_frame_) : 0.5 * proven_avg_ + 0.5 * double(proven_frame_);
  const double need = policy_.min_decided_screens * ctx_.width() * ctx_.height();
  use_pyramid_ = need == 0 || proven_avg_ < 0 || proven_avg_ >= need || ++frames_off_ % kRetryFrames == 0;
  if (use_pyramid_) frames_off_ = 0;
  proven_frame_ = 0;
  cam_ = cam;
  built_ = stale_ = false;
  dirty_.clear();
  counted_begin(cam);
}

void CpuPyramidTests::depth_added(std::span<const Aabb> drawn) {
  stale_ = built_;
  const int w = ctx_.width(), h = ctx_.height();
  if (drawn.empty()) dirty_.add({0, 0, w - 1, h - 1});
  for (const Aabb& box : drawn) dirty_.add_box(box, cam_, {w, h});
  counted_begin(cam_);
}

void CpuPyramidTests::refresh() {
  const int w = ctx_.width(), h = ctx_.height();
  if (!built_) {
    ctx_.read_depth(pyramid_.level0(w, h));
    pyramid_.build_levels();
    built_ = true;
    stale_ = false;
    dirty_.clear();
    ++stats_.builds;
    return;
  }
  if (dirty_.empty()) return;
  double boxes = 0;
  for (const PyramidProbe& p : batch_.probes)
    boxes += p.kind == PyramidProbe::Kind::probe ? double(probe_pixels(p))
             : p.kind == PyramidProbe::Kind::query ? double(w) * h
                                                   : 0.0;
  if (dirty_.pixels() > boxes) return;
  const PixelRect& d = dirty_;
  ctx_.read_depth(d.x0, d.y0, d.x1 - d.x0 + 1, d.y1 - d.y0 + 1, pyramid_.level0(w, h));
  pyramid_.build_levels(d.x0, d.y0, d.x1, d.y1);
  stale_ = false;
  dirty_.clear();
  ++stats_.refreshes;
}

uint32_t CpuPyramidTests::issue(const Aabb& box) {
  ++stats_.tests;
  if (!use_pyramid_) return counted_issue(box);
  return batch_.add(box, false, cam_, {ctx_.width(), ctx_.height()}, policy_.span);
}

uint32_t CpuPyramidTests::issue_cheap(const Aabb& box) {
  if (!use_pyramid_) throw std::logic_error("CpuPyramidTests: issue_cheap() in a frame without the pyramid (cheap_tests())");
  ++stats_.tests;
  ++stats_.cheap;
  return batch_.add(box, true, cam_, {ctx_.width(), ctx_.height()}, policy_.span);
}

void CpuPyramidTests::resolve() {
  batch_.resolve_start();
  refresh();
  if (!batch_.sent.empty()) {
    batch_.occluded.resize(batch_.sent.size());
    for (size_t j = 0; j < batch_.sent.size(); ++j) batch_.occluded[j] = pyramid_.occludes(batch_.sent[j]);
    stats_.pyramid_tested += batch_.sent.size();
    uint64_t pixels = 0;
    stats_.pyramid_occluded += batch_.take_occluded(pixels);
    stats_.pyramid_pixels += pixels;
    proven_frame_ += pixels;
  }
  stats_.assumed += batch_.assume_cheap();
  // Without sample counts the pyramid also proves boxes that show, from level 0, which must be
  // the current depth under the box: not where occluder fusion drew since it was read.
  if (!sample_counts_)
    for (size_t i = 0; i < batch_.boxes.size(); ++i)
      if (batch_.answer[i] == PyramidBatch::kPending && clean_under(batch_.boxes[i]) &&
          pyramid_.shows(batch_.boxes[i], cam_)) {
        batch_.answer[i] = PyramidBatch::kShows;
        ++stats_.shown;
        proven_frame_ += batch_.probes[i].kind == PyramidProbe::Kind::probe
                             ? probe_pixels(batch_.probes[i])
                             : uint64_t(ctx_.width()) * uint64_t(ctx_.height());
      }
  for (size_t i = 0; i < batch_.boxes.size(); ++i)
    if (batch_.answer[i] == PyramidBatch::kPending) batch_.answer[i] = counted_issue(batch_.boxes[i]);
}

bool CpuPyramidTests::clean_under(const Aabb& box) const {
  return dirty_.empty() || !dirty_.touches(box_footprint(box, cam_, {ctx_.width(), ctx_.height()}));
}

uint64_t CpuPyramidTests::result(uint32_t handle) {
  uint64_t samples = 0;
  if (!use_pyramid_) {
    samples = counted_result(handle);
  } else {
    if (!batch_.resolved) resolve();
    const uint32_t a = batch_.at(handle);
    samples = a == PyramidBatch::kZero                                   ? 0
              : a == PyramidBatch::kShows || a == PyramidBatch::kAssumed ? 1
                                                                         : counted_result(a);
  }
  stats_.occluded += samples == 0;
  return samples;
}

void CpuPyramidTests::counted_begin(const Camera& cam) {
  counter_.begin(cam);
  queries_.begin(cam);  // last: its program is bound for issue()
}

uint32_t CpuPyramidTests::counted_issue(const Aabb& box) {
  // Boxes covering many pixels (or possibly the whole view) are cheaper as queries: every
  // fragment of the batch draw that passes runs the counting shader.
  const BoxFootprint fp = box_footprint(box, cam_, {ctx_.width(), ctx_.height()});
  const bool big = fp.kind == BoxFootprint::Kind::NearPlane ||
                   (fp.kind == BoxFootprint::Kind::OnScreen &&
                    double(fp.x1 - fp.x0 + 1) * double(fp.y1 - fp.y0 + 1) > policy_.batch_max_pixels);
  if (!big) {
    ++stats_.batched;
    return counter_.issue(box);
  }
  ++stats_.queries;
  return queries_.issue(box) | kQueryBit;
}

uint64_t CpuPyramidTests::counted_result(uint32_t h) {
  if (h & kQueryBit) {
    if (!counter_.drawn()) counter_.draw();  // the batch draw first: one flush for both
    return queries_.result(h & ~kQueryBit);
  }
  return counter_.result(h);
}

void CpuPyramidTests::end_batch() {
  queries_.reset();
  if (counter_.drawn()) queries_.begin(cam_);  // the batch draw bound its own program
  counter_.reset();
  stats_.draws = counter_.draws();
  batch_.clear();
}

OcclusionCounts CpuPyramidTests::counts() const {
  const Stats& q = stats_;
  const auto n = [](uint64_t v) { return std::to_string(v); };
  char mp[32];
  std::snprintf(mp, sizeof mp, "%.2f", double(q.pyramid_pixels) / 1e6);
  OcclusionCounts c;
  c.boxes_tested = q.tests;
  c.boxes_occluded = q.occluded;
  c.more.push_back(n(q.queries) + " occlusion queries issued");
  c.more.push_back(n(q.batched) + " boxes in " + n(q.draws) + " batch draws");
  c.more.push_back(n(q.pyramid_occluded) + " proven occluded by the depth pyramid (" + mp +
                   " M pixels of their rectangles) and " + n(q.shown) + " shown, of " + n(q.pyramid_tested) +
                   " tested against it; " + n(q.builds) + " pyramid builds, " + n(q.refreshes) +
                   " refreshes after occluder fusion");
  if (q.cheap) c.more.push_back(n(q.assumed) + " of " + n(q.cheap) + " skipped by adaptive queries assumed visible");
  return c;
}

}  // namespace occ
