// The occlusion switch's worst case: the eye walks out of a closed room, through its
// wall, into a dense field of cubes. Nothing the room showed last frame hides the field, so an HC
// that only tests against the OR's depth (the room) finds everything in the frustum visible: a
// frame that draws hundreds of cubes where a handful show. HC's occluder fusion (near-first
// batches, each drawing what it found before the next is queried) must keep every frame within a
// few times the exactly visible set, and the frames equal to the reference.
#include <gtest/gtest.h>

#include "hard_util.hpp"

using namespace occtest;

namespace {

std::vector<occ::Camera> exit_path() {
  std::vector<occ::Camera> path;
  for (int f = 0; f < 24; ++f) {
    const double x = 1.0 + 0.22 * f, z = 2.0 + 0.05 * f;  // through the room's +x wall at x = 4
    path.push_back(cam({x, 1.5, z}, {x + 10, 1.4, z + 1.5}, 70, 0.05, 200));
  }
  return path;
}

}  // namespace

TEST(HardExit, LeavingAClosedRoomNeverDrawsMoreThanAFewTimesTheVisibleSet) {
  const View view{128, 128};
  const fs::path dir = expect_cluster_equals_reference("exit", "hard:exit", exit_path(), view);
  // The exactly visible leaves of every frame (item buffer), against what the RVG drew.
  const std::string csv = (dir / "path.csv").string();
  Proc exact({bin("render_client"), "--exact", "--cull", "none", "--images", "off", "--scene", "hard:exit",
              "--path", csv, "--out", (dir / "exact").string(), "--width", "128", "--height", "128"},
             dir / "exact.log");
  ASSERT_EQ(exact.wait(120s), 0) << exact.log();
  const auto ex = read_csv(dir / "exact" / "stats.csv");
  const auto cl = read_csv(dir / "cluster" / "stats.csv");
  ASSERT_EQ(ex.at("exact_visible").size(), cl.at("visible").size());
  bool left_the_room = false;
  for (size_t f = 0; f < ex.at("exact_visible").size(); ++f) {
    const double exact_v = ex.at("exact_visible")[f], drawn = cl.at("visible")[f];
    EXPECT_GE(drawn, exact_v) << "frame " << f << ": the cluster drew fewer leaves than are visible";
    EXPECT_LE(drawn, 3 * std::max(exact_v, 1.0) + 2) << "frame " << f << ": " << drawn << " leaves drawn, "
                                                     << exact_v << " visible";
    left_the_room |= exact_v >= 3;
  }
  EXPECT_TRUE(left_the_room) << "the path should end outside the room, seeing cubes";
}
