#include "common/cull/raster_queries.hpp"

#include <algorithm>

namespace occ {

namespace {
// The pad of the renderer's query box (BoxQuerier::kRelativePad), so both rasterise the same box.
constexpr double kRelativePad = 1e-5;
// Probe rectangles of up to kSpan x kSpan texels (the GL pyramid tests' policy): the pyramid only proves
// what it proves at a glance; the rest goes to the box's faces.
constexpr int kSpan = 16;
}  // namespace

void RasterQueries::begin(const Camera& cam) {
  cam_ = cam;
  const DepthRaster& r = occ_.raster();
  const std::span<const float> d = r.depth();
  std::copy(d.begin(), d.end(), pyramid_.level0(r.width(), r.height()));
  pyramid_.build_levels();
  dirty_.clear();
  answers_.clear();
}

void RasterQueries::depth_added(std::span<const Aabb> drawn) {
  for (const Aabb& box : drawn) dirty_.add_box(box, cam_, {occ_.raster().width(), occ_.raster().height()});
}

bool RasterQueries::pyramid_hides(const Aabb& box) {
  if (!dirty_.empty()) {  // level 0 from the raster where fusion drew, the levels above it
    const DepthRaster& r = occ_.raster();
    const int w = r.width();
    float* level0 = pyramid_.level0(w, r.height());
    for (int y = dirty_.y0; y <= dirty_.y1; ++y) {
      const size_t row = size_t(y) * size_t(w);
      std::copy(r.depth().begin() + ptrdiff_t(row + size_t(dirty_.x0)), r.depth().begin() + ptrdiff_t(row + size_t(dirty_.x1) + 1),
                level0 + row + size_t(dirty_.x0));
    }
    pyramid_.build_levels(dirty_.x0, dirty_.y0, dirty_.x1, dirty_.y1);
    dirty_.clear();
  }
  const PyramidProbe p = pyramid_probe(box, cam_, {pyramid_.width(), pyramid_.height()}, kRelativePad, kSpan);
  if (p.kind == PyramidProbe::Kind::no_samples || (p.kind == PyramidProbe::Kind::probe && pyramid_.occludes(p))) {
    ++stats_.pyramid_occluded;
    return true;
  }
  return false;
}

uint32_t RasterQueries::answer(uint64_t samples) {
  answers_.push_back(samples > 0 ? 1 : 0);
  return uint32_t(answers_.size() - 1);
}

uint32_t RasterQueries::issue(const Aabb& box) {
  ++stats_.tests;
  if (pyramid_hides(box)) return answer(0);
  if (occ_.box_shows(box, kRelativePad)) return answer(1);
  ++stats_.raster_occluded;
  return answer(0);
}

uint32_t RasterQueries::issue_cheap(const Aabb& box) {
  ++stats_.tests;
  return answer(pyramid_hides(box) ? 0 : 1);
}

}  // namespace occ
