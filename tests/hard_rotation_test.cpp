// Camera orientation from many concatenated small rotations: Camera::rotate_local
// re-normalises after every step, so a million small turns end where the directly computed
// orientation is, and a path built that way renders through the three real processes exactly
// like the directly computed path (reference renderer).
#include <gtest/gtest.h>

#include <glm/gtc/quaternion.hpp>

#include "hard_util.hpp"

using namespace occtest;
using occ::Camera;

namespace {

// A tilted axis so that every component of the quaternion changes.
const glm::dvec3 kAxis = glm::normalize(glm::dvec3(0.3, 1.0, 0.2));
constexpr double kStep = 1e-5;  // radians per small rotation

Camera start() { return Camera::look_at({-12, 1.5, 0}, {0, 1.5, 0}, {0, 1, 0}, 60, 1.0, 0.05, 500); }

// The angle between two orientations (radians).
double angle_between(const glm::dquat& a, const glm::dquat& b) {
  const glm::dquat r = glm::conjugate(glm::normalize(a)) * glm::normalize(b);  // a^-1 b
  return 2.0 * std::asin(std::min(1.0, glm::length(glm::dvec3(r.x, r.y, r.z))));  // precise for small angles
}

}  // namespace

TEST(HardRotation, MillionSmallRotationsStayUnitAndMatchTheDirectOrientation) {
  constexpr int kSteps = 1000000;
  Camera c = start();
  glm::dquat raw = c.orientation;  // the same chain without re-normalising, for the figures
  glm::quat single(c.orientation);  // and in single precision without re-normalising
  const glm::dquat delta = glm::angleAxis(kStep, kAxis);
  for (int i = 0; i < kSteps; ++i) {
    c.rotate_local(delta);
    raw = raw * delta;
    single = single * glm::quat(delta);
  }
  const glm::dquat direct = start().orientation * glm::angleAxis(kStep * kSteps, kAxis);
  const double err = angle_between(c.orientation, direct);
  std::cout << "[ figures  ] after " << kSteps << " rotations: re-normalised |q|-1 = " << glm::length(c.orientation) - 1
            << ", angle error " << err << " rad; not re-normalised (double) |q|-1 = " << glm::length(raw) - 1
            << "; not re-normalised (float) |q|-1 = " << glm::length(single) - 1.0f << "\n";
  EXPECT_LT(std::abs(glm::length(c.orientation) - 1.0), 1e-14);
  EXPECT_LT(err, 1e-10);
  EXPECT_FALSE(c.invalid_reason().has_value()) << *c.invalid_reason();
  // The camera axes stay orthonormal.
  EXPECT_NEAR(glm::dot(c.forward(), c.up()), 0.0, 1e-12);
  EXPECT_NEAR(glm::length(c.right()), 1.0, 1e-12);
}

TEST(HardRotation, ConcatenatedPathRendersLikeTheDirectPathThroughTheCluster) {
  // Frame k: 20000 * k small turns (0.2 rad per frame) concatenated, versus computed directly.
  constexpr int kFrames = 8, kStepsPerFrame = 20000;
  const glm::dquat delta = glm::angleAxis(kStep, kAxis);
  std::vector<Camera> chained, direct;
  Camera c = start();
  for (int f = 0; f < kFrames; ++f) {
    chained.push_back(c);
    Camera d = start();
    d.orientation = start().orientation * glm::angleAxis(kStep * kStepsPerFrame * f, kAxis);
    direct.push_back(d);
    for (int i = 0; i < kStepsPerFrame; ++i) c.rotate_local(delta);
    EXPECT_LT(angle_between(chained.back().orientation, d.orientation), 1e-9) << "frame " << f;
  }
  const fs::path dir = expect_cluster_equals_reference("rotation", "hard:walls", chained);
  const View view;
  const std::string csv = write_path(dir / "direct.csv", direct);
  const Outcome ref = run_reference(dir / "direct", "hard:walls", csv, unculled(view));
  ASSERT_EQ(ref.code, 0) << ref.log;
  const Outcome diff = frame_diff(dir / "direct", dir / "cluster");
  EXPECT_EQ(diff.code, 0) << "chained != direct\n" << differing_frames(diff.log);
}
