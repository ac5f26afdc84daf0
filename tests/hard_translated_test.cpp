// Scenes far from the origin: the same scene translated by 1e4, 1e6 and 1e7 units
// (offset:DX,DY,DZ:<spec>, which moves the double-precision object transforms) seen by the same
// cameras translated alike. Eye positions are double and rendering is camera-relative
// (SceneRenderer subtracts the eye in double before rounding to float; BoxQuerier does the same
// for boxes), so:
//   1. the cluster equals the reference on the translated scene (conservative culling), and
//   2. the translated frames equal the untranslated reference frames up to float rounding of the
//      camera-relative transforms: the budget is 0.2% of the pixels differing by more than 8/255
//      in a channel (an edge pixel whose coverage flips), and the count of background pixels may
//      not grow by more than that either: a missing (falsely culled or cracked) object shows as
//      background, a z-fighting one as many differing pixels.
#include <gtest/gtest.h>

#include "hard_util.hpp"

using namespace occtest;
using occ::Camera;

namespace {

constexpr double kBudgetFraction = 0.002;
constexpr int kBudgetThreshold = 8;

void expect_translation_invariant(const std::string& name, const std::string& inner_spec,
                                  const std::vector<Camera>& path, const std::vector<double>& offsets) {
  const View view;
  const fs::path dir = fresh_dir("hard_translated_" + name);
  const std::string base_csv = write_path(dir / "path.csv", path);
  const Outcome untranslated = run_reference(dir / "untranslated", inner_spec, base_csv, unculled(view));
  ASSERT_EQ(untranslated.code, 0) << untranslated.log;
  const double pixels = double(view.width) * view.height;
  for (double d : offsets) {
    const glm::dvec3 offset(d, 0.5 * d, -d);
    char spec[128];
    std::snprintf(spec, sizeof spec, "offset:%.17g,%.17g,%.17g:", offset.x, offset.y, offset.z);
    const std::string scene = spec + inner_spec;
    SCOPED_TRACE(scene);
    const fs::path sub = dir / ("offset_" + std::to_string(int(std::log10(d))));
    fs::create_directories(sub);
    const std::string csv = write_path(sub / "path.csv", translated(path, offset));
    if (!expect_cluster_equals_reference(sub, hard_cluster(scene, csv, view), unculled(view), path.size())) return;
    const Outcome budget = frame_diff(dir / "untranslated", sub / "cluster",
                                      {"--max-fraction", std::to_string(kBudgetFraction), "--threshold",
                                       std::to_string(kBudgetThreshold)});
    EXPECT_EQ(budget.code, 0) << "translated cluster frames differ from the untranslated reference beyond the budget\n"
                              << budget.log;
    const Outcome strict = frame_diff(dir / "untranslated", sub / "cluster");
    std::cout << "[ figures  ] " << scene << ": translated vs untranslated, exact comparison: "
              << diff_summary(strict.log) << "\n";
    size_t max_extra = 0;
    for (size_t f = 0; f < path.size(); ++f) {
      const size_t base = background_pixels(dir / "untranslated", f), moved = background_pixels(sub / "cluster", f);
      EXPECT_LE(double(moved), double(base) + kBudgetFraction * pixels)
          << "frame " << f << ": " << moved << " background pixels, untranslated " << base;
      if (moved > base) max_extra = std::max(max_extra, moved - base);
    }
    std::cout << "[ figures  ] " << scene << ": most extra background pixels in a frame: " << max_extra << "\n";
  }
}

std::vector<Camera> walls_path() {
  return {
      cam({-12, 1.5, 0}, {0, 1.5, 0}),       cam({-6.5, 1.5, 0}, {10, 1.5, 0}),  // inside the open box
      cam({-5, 1.5, 0}, {10, 1.5, 0.2}),                                         // on its face plane
      cam({9.9, 2, 3}, {20, 2, 3}),          cam({9.96, 2, 3}, {20, 2, 3}),      // near plane crosses wall 1
      cam({10, 2, 3}, {20, 2, 3}),           cam({10.04, 2, 3}, {20, 2, 3}),     // on it, through it
      cam({15, 0.5, 0}, {0, 0.5, 0}),                                            // inside a cube
      cam({-2, 2, 8}, {60, 2, 8}),                                               // edge-on wall
      cam({-300, 1.3, 2.8}, {50, 0.8, 2.9}, 2.0, 1e-3, 1e6),                     // near 1e-3, far 1e6
      cam({9.998, 2, 3}, {20, 2, 3}, 60, 1e-3, 1e6),
      cam({25, 30, -20}, {25, 0, 0}),                                            // from above
  };
}

}  // namespace

TEST(HardTranslated, WallsAt1e4And1e6And1e7RenderLikeTheUntranslatedScene) {
  expect_translation_invariant("walls", "hard:walls", walls_path(), {1e4, 1e6, 1e7});
}

TEST(HardTranslated, TinyPartsInAHugeHallAt1e7RenderLikeTheUntranslatedScene) {
  std::vector<Camera> p = {
      cam({-0.02, 1.002, 0.001}, {0, 1.002, 0.001}, 40, 1e-4, 2e5),
      cam({-0.005, 1.0005, 0.0005}, {0.001, 1.0005, 0.0005}, 60, 1e-4, 2e5),
      cam({-3, 2, -1}, {5, 1, 0}, 60, 1e-3, 2e5),
      cam({-4e4, 1e4, -4e4}, {0, 0, 0}, 60, 1.0, 2e5),
  };
  expect_translation_invariant("span", "hard:span", p, {1e7});
}
