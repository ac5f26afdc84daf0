#include <gtest/gtest.h>

#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>

#include "common/camera.hpp"
#include "common/math.hpp"
#include "random_util.hpp"

using namespace occ;

namespace {
Camera looking_down_minus_z() {
  return Camera::look_at({0, 0, 0}, {0, 0, -1}, {0, 1, 0}, 90.0, 1.0, 0.1, 100.0);
}
Aabb box(glm::dvec3 lo, glm::dvec3 hi) { return Aabb{lo, hi}; }
}  // namespace

TEST(Frustum, BoxInFrontIsInside) {
  EXPECT_EQ(looking_down_minus_z().frustum().classify(box({-1, -1, -6}, {1, 1, -4})), Containment::Inside);
}

TEST(Frustum, BoxBehindEyeIsCulled) {
  EXPECT_TRUE(looking_down_minus_z().frustum().culls(box({-1, -1, 4}, {1, 1, 6})));
}

TEST(Frustum, BoxBehindNearPlaneIsCulled) {
  EXPECT_TRUE(looking_down_minus_z().frustum().culls(box({-0.01, -0.01, -0.05}, {0.01, 0.01, -0.01})));
}

TEST(Frustum, BoxCrossingNearPlaneIntersects) {
  EXPECT_EQ(looking_down_minus_z().frustum().classify(box({-1, -1, -1}, {1, 1, 1})), Containment::Intersects);
}

TEST(Frustum, BoxBeyondFarIsCulled) {
  EXPECT_TRUE(looking_down_minus_z().frustum().culls(box({-1, -1, -300}, {1, 1, -200})));
}

TEST(Frustum, BoxOutsideSidePlaneIsCulledAndTouchingIsNot) {
  Frustum f = looking_down_minus_z().frustum();  // 90 degrees: side planes are x = +-|z|
  EXPECT_TRUE(f.culls(box({6, -1, -5}, {8, 1, -4})));
  EXPECT_FALSE(f.culls(box({5, -1, -6}, {8, 1, -5})));  // touches x = 5 at z = -5
}

TEST(Frustum, EmptyBoxIsCulled) { EXPECT_TRUE(looking_down_minus_z().frustum().culls(Aabb{})); }

TEST(Aabb, ContainsIsClosedAndDistanceIsZeroInside) {
  Aabb b = box({0, 0, 0}, {1, 1, 1});
  EXPECT_TRUE(b.contains({1, 0.5, 0}));
  EXPECT_FALSE(b.contains({1.0001, 0.5, 0}));
  EXPECT_EQ(b.distance2({0.5, 0.5, 0.5}), 0.0);
  EXPECT_DOUBLE_EQ(b.distance2({3, 0.5, 0.5}), 4.0);
}

TEST(Aabb, TransformedEnclosesRotatedCorners) {
  Aabb b = box({-1, -1, -1}, {1, 1, 1});
  glm::dmat4 m = glm::rotate(glm::dmat4(1.0), glm::radians(45.0), glm::dvec3(0, 1, 0));
  Aabb t = b.transformed(m);
  EXPECT_NEAR(t.max.x, std::sqrt(2.0), 1e-12);
  EXPECT_NEAR(t.max.y, 1.0, 1e-12);
}

TEST(Camera, ReverseZMapsNearToOneAndFarToZero) {
  Camera c = looking_down_minus_z();
  glm::dmat4 vp = c.projection() * c.view_rotation();
  glm::dvec4 n = vp * glm::dvec4(0, 0, -c.near_dist, 1), f = vp * glm::dvec4(0, 0, -c.far_dist, 1);
  EXPECT_NEAR(n.z / n.w, 1.0, 1e-12);
  EXPECT_NEAR(f.z / f.w, 0.0, 1e-12);
}

TEST(Camera, LookAtAxesAreOrthonormal) {
  Camera c = Camera::look_at({1e7, 3, -2e6}, {1e7 + 3, 4, -2e6 - 5}, {0, 1, 0}, 50, 1.5, 0.01, 1e5);
  EXPECT_NEAR(glm::length(c.forward()), 1.0, 1e-12);
  EXPECT_NEAR(glm::dot(c.forward(), c.up()), 0.0, 1e-12);
  EXPECT_NEAR(glm::dot(c.forward(), glm::normalize(glm::dvec3(3, 1, -5))), 1.0, 1e-12);
  EXPECT_FALSE(c.invalid_reason());
}

TEST(Camera, LookAtWithUpParallelToViewStillGivesValidCamera) {
  Camera c = Camera::look_at({0, 10, 0}, {0, 0, 0}, {0, 1, 0}, 60, 1, 0.1, 100);
  EXPECT_FALSE(c.invalid_reason());
  EXPECT_NEAR(c.forward().y, -1.0, 1e-12);
}

TEST(Camera, InvalidValuesAreNamed) {
  Camera c = looking_down_minus_z();
  c.near_dist = 0;
  EXPECT_EQ(*c.invalid_reason(), "near <= 0 or non-finite");
  c = looking_down_minus_z();
  c.far_dist = c.near_dist;
  EXPECT_EQ(*c.invalid_reason(), "far <= near or non-finite");
  c = looking_down_minus_z();
  c.eye.x = NAN;
  EXPECT_EQ(*c.invalid_reason(), "non-finite eye position");
  c = looking_down_minus_z();
  c.orientation = glm::dquat(0, 0, 0, 0);
  EXPECT_TRUE(c.invalid_reason());
}

TEST(Camera, FrustumAgreesWithProjectionOnRandomPoints) {
  Camera c = Camera::look_at({2, 1, 3}, {0, 0, 0}, {0, 1, 0}, 70, 1.7, 0.5, 50);
  Frustum f = c.frustum();
  glm::dmat4 vp = c.projection() * c.view_rotation();
  occtest::Lcg rnd{12345};
  for (int i = 0; i < 20000; ++i) {
    glm::dvec3 p(rnd() * 80 - 40, rnd() * 80 - 40, rnd() * 80 - 40);
    glm::dvec4 clip = vp * glm::dvec4(p - c.eye, 1.0);
    bool in_clip = clip.w > 0 && std::abs(clip.x) <= clip.w && std::abs(clip.y) <= clip.w && clip.z >= 0 && clip.z <= clip.w;
    bool in_planes = true;
    for (auto& pl : f.planes) in_planes = in_planes && pl.distance(p) >= 0;
    double margin = 1e-9 * clip.w;
    if (std::abs(std::abs(clip.x) - clip.w) < margin || std::abs(std::abs(clip.y) - clip.w) < margin) continue;
    EXPECT_EQ(in_clip, in_planes) << "point " << p.x << "," << p.y << "," << p.z;
  }
}
