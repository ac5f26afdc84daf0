// The --window camera control (render_client/navigator.hpp): keys, drags and the wheel in, a
// Camera out. No GL, no X.
#include <gtest/gtest.h>

#include <cmath>

#include "common/camera_path.hpp"
#include "render_client/navigator.hpp"

using namespace occ;

namespace {
const Aabb kBounds{{-50, 0, -50}, {50, 30, 50}};
// At eye height, looking along -Z (yaw 0) and a little down.
Camera home() {
  Camera c = Camera::look_at({0, 2, 10}, {0, 1, 0}, {0, 1, 0}, 60, 4.0 / 3.0, 0.1, 1.0);
  auto_near_far(c, kBounds);
  return c;
}
}  // namespace

TEST(Navigator, StartsAtHomeAndKeepsItsView) {
  Navigator n(home(), kBounds);
  const Camera c = n.camera();
  EXPECT_NEAR(glm::length(c.eye - home().eye), 0, 1e-12);
  EXPECT_NEAR(glm::dot(c.forward(), home().forward()), 1, 1e-12);
  EXPECT_DOUBLE_EQ(c.fovy_rad, home().fovy_rad);
  EXPECT_DOUBLE_EQ(c.aspect, home().aspect);
  EXPECT_FALSE(c.invalid_reason());
  EXPECT_NEAR(c.up().y, std::cos(std::asin(-home().forward().y)) , 1e-9);  // no roll
}

TEST(Navigator, TapMovesOneStepForwardAndHeldKeyMovesWithTime) {
  Navigator n(home(), kBounds);
  const glm::dvec3 f = home().forward();
  n.press(NavKey::forward);
  n.press(NavKey::forward);  // auto-repeat: no second step
  const double tap = n.speed() * Navigator::kTapSeconds;
  EXPECT_NEAR(glm::length(n.camera().eye - (home().eye + f * tap)), 0, 1e-9);
  n.advance(0.5);
  EXPECT_NEAR(glm::length(n.camera().eye - (home().eye + f * (tap + 0.5 * n.speed()))), 0, 1e-9);
  n.release(NavKey::forward);
  const glm::dvec3 stopped = n.camera().eye;
  n.advance(1.0);
  EXPECT_EQ(n.camera().eye, stopped);
  EXPECT_FALSE(n.moving());
}

TEST(Navigator, StrafeUpDownAndShift) {
  Navigator n(home(), kBounds);
  const double tap = n.speed() * Navigator::kTapSeconds;
  n.press(NavKey::right);
  n.release(NavKey::right);
  EXPECT_NEAR(n.camera().eye.x - home().eye.x, tap, 1e-9);  // yaw 0: right is +X
  n.press(NavKey::up);
  n.release(NavKey::up);
  EXPECT_NEAR(n.camera().eye.y - home().eye.y, tap, 1e-9);
  n.press(NavKey::fast);
  n.press(NavKey::left);
  n.release(NavKey::left);
  EXPECT_NEAR(n.camera().eye.x - home().eye.x, tap - Navigator::kFastFactor * tap, 1e-9);
}

TEST(Navigator, WalkKeepsEyeHeightWhileLookingDownFlyDoesNot) {
  Navigator n(home(), kBounds);
  ASSERT_LT(home().forward().y, -0.05);  // looks down
  n.toggle_walk();
  ASSERT_TRUE(n.walking());
  n.press(NavKey::forward);
  n.advance(2.0);
  n.release(NavKey::forward);
  EXPECT_DOUBLE_EQ(n.camera().eye.y, home().eye.y);
  EXPECT_LT(n.camera().eye.z, home().eye.z - 1);
  n.toggle_walk();
  n.press(NavKey::forward);
  n.release(NavKey::forward);
  EXPECT_LT(n.camera().eye.y, home().eye.y);
}

TEST(Navigator, DragAndArrowsTurnPitchIsClampedResetReturnsHome) {
  Navigator n(home(), kBounds);
  const double yaw0 = n.yaw_deg();
  n.drag(40, 0);  // drag right: look right (yaw decreases)
  EXPECT_NEAR(n.yaw_deg(), yaw0 - 40 * Navigator::kDragDegPerPixel, 1e-9);
  EXPECT_GT(n.camera().forward().x, 0.1);
  n.press(NavKey::look_left);
  n.release(NavKey::look_left);
  EXPECT_NEAR(n.yaw_deg(), yaw0 - 40 * Navigator::kDragDegPerPixel + Navigator::kTurnDegPerSecond * Navigator::kTapSeconds, 1e-9);
  n.drag(0, -100000);  // far up
  EXPECT_NEAR(n.pitch_deg(), 89, 1e-9);
  EXPECT_FALSE(n.camera().invalid_reason());
  n.wheel(3);
  n.reset();
  EXPECT_NEAR(glm::dot(n.camera().forward(), home().forward()), 1, 1e-12);
  EXPECT_EQ(n.camera().eye, home().eye);
  EXPECT_FALSE(n.walking());
}

TEST(Navigator, WheelScalesSpeedAndChangesCount) {
  Navigator n(home(), kBounds);
  const double s0 = n.speed();
  const uint64_t c0 = n.changes();
  n.wheel(2);
  EXPECT_NEAR(n.speed(), s0 * Navigator::kWheelFactor * Navigator::kWheelFactor, 1e-12);
  n.wheel(-2);
  EXPECT_NEAR(n.speed(), s0, 1e-12);
  EXPECT_GT(n.changes(), c0);
}

TEST(Navigator, JumpToFollowsAPathCameraAndNearFarFollowTheEye) {
  Navigator n(home(), kBounds);
  const auto path = load_camera_path("orbit:4", kBounds, {320, 240});
  n.jump_to(path[1]);
  const Camera c = n.camera();
  EXPECT_NEAR(glm::length(c.eye - path[1].eye), 0, 1e-9);
  EXPECT_NEAR(glm::dot(c.forward(), path[1].forward()), 1, 1e-12);
  EXPECT_DOUBLE_EQ(c.far_dist, path[1].far_dist);  // auto_near_far at the same eye
}

// An unknown --path kind says so (not "cannot open camera path file").
TEST(CameraPathSpec, UnknownKindAndMissingCountSaySo) {
  auto error_of = [](const std::string& spec) -> std::string {
    try {
      load_camera_path(spec, kBounds, {64, 48});
    } catch (const std::exception& e) {
      return e.what();
    }
    return "";
  };
  EXPECT_EQ(error_of("spiral:10"), "--path 'spiral:10': unknown kind 'spiral' (expected orbit:N, walk:N, fly:N or a CSV file)");
  EXPECT_EQ(error_of("walk"), "--path 'walk': give a frame count, e.g. walk:60");
  EXPECT_NE(error_of("/nonexistent/p.csv").find("cannot open camera path file"), std::string::npos);
  EXPECT_EQ(error_of("walk:3"), "");
}
