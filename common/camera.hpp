// Camera: eye in double precision (large coordinates), orientation as a unit quaternion
// (camera space: looks down -Z, +Y up, +X right), vertical field of view, aspect, near, far.
// Rendering is camera-relative: the view matrix has no translation; geometry is shifted by
// -eye in double before it becomes float (see SceneRenderer), so far-from-origin scenes do not
// crack. Projection is reverse-Z (near -> depth 1, far -> depth 0) for a float depth buffer.
#pragma once
#include <optional>
#include <string>

#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>

#include "common/math.hpp"
#include "common/section.hpp"

namespace occ {

struct Viewport {
  int width = 0;
  int height = 0;
  bool operator==(const Viewport&) const = default;
};
constexpr int kMaxViewportPx = 16384;

struct Camera {
  glm::dvec3 eye{0.0};
  glm::dquat orientation{1.0, 0.0, 0.0, 0.0};  // camera -> world rotation (w, x, y, z)
  double fovy_rad = glm::radians(60.0);
  double aspect = 1.0;
  double near_dist = 0.1;
  double far_dist = 1000.0;
  Sections sections;  // what the view keeps of the scene (section.hpp); none: all of it

  static Camera look_at(const glm::dvec3& eye, const glm::dvec3& target, const glm::dvec3& up,
                        double fovy_deg, double aspect, double near_dist, double far_dist);

  glm::dvec3 forward() const { return orientation * glm::dvec3(0, 0, -1); }
  glm::dvec3 up() const { return orientation * glm::dvec3(0, 1, 0); }
  glm::dvec3 right() const { return orientation * glm::dvec3(1, 0, 0); }

  // Turns the camera by `delta`, a rotation in camera space (orientation = orientation * delta),
  // and re-normalises the quaternion, so that a long chain of small rotations (an interactive
  // walk) stays a unit quaternion and does not drift from the directly computed orientation.
  void rotate_local(const glm::dquat& delta);

  // World-to-camera rotation only (eye at the origin): use with camera-relative positions.
  glm::dmat4 view_rotation() const;
  // Reverse-Z projection for glClipControl(GL_LOWER_LEFT, GL_ZERO_TO_ONE): near -> 1, far -> 0.
  glm::dmat4 projection() const;
  // World-space frustum planes computed directly from the camera (double, no matrix inversion),
  // with the section planes as its cuts.
  Frustum frustum() const;

  // nullopt when valid, else a reason ("near <= 0", "non-finite eye", ...).
  std::optional<std::string> invalid_reason() const;
  bool operator==(const Camera&) const = default;
};

}  // namespace occ
