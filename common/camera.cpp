#include "common/camera.hpp"

#include <cmath>

#include <glm/gtc/matrix_transform.hpp>

namespace occ {

Camera Camera::look_at(const glm::dvec3& eye, const glm::dvec3& target, const glm::dvec3& up,
                       double fovy_deg, double aspect, double near_dist, double far_dist) {
  Camera c;
  c.eye = eye;
  glm::dvec3 f = target - eye;
  double fl = glm::length(f);
  f = fl > 0 ? f / fl : glm::dvec3(0, 0, -1);
  glm::dvec3 r = glm::cross(f, up);
  double rl = glm::length(r);
  if (!(rl > 1e-12)) {  // up parallel to forward: pick any perpendicular
    r = glm::cross(f, std::abs(f.y) < 0.9 ? glm::dvec3(0, 1, 0) : glm::dvec3(1, 0, 0));
    rl = glm::length(r);
  }
  r /= rl;
  glm::dvec3 u = glm::cross(r, f);
  glm::dmat3 m(r, u, -f);  // columns: camera axes in world space
  c.orientation = glm::normalize(glm::quat_cast(m));
  c.fovy_rad = glm::radians(fovy_deg);
  c.aspect = aspect;
  c.near_dist = near_dist;
  c.far_dist = far_dist;
  return c;
}

void Camera::rotate_local(const glm::dquat& delta) { orientation = glm::normalize(orientation * delta); }

glm::dmat4 Camera::view_rotation() const {
  return glm::dmat4(glm::mat3_cast(glm::conjugate(orientation)));
}

glm::dmat4 Camera::projection() const {
  const double f = 1.0 / std::tan(fovy_rad * 0.5);
  const double n = near_dist, fa = far_dist;
  glm::dmat4 p(0.0);
  p[0][0] = f / aspect;
  p[1][1] = f;
  p[2][2] = n / (fa - n);
  p[2][3] = -1.0;
  p[3][2] = n * fa / (fa - n);
  return p;
}

Frustum Camera::frustum() const {
  const glm::dvec3 fw = forward(), up_v = up(), rt = right();
  const double ty = std::tan(fovy_rad * 0.5), tx = ty * aspect;
  auto make = [&](glm::dvec3 n, const glm::dvec3& point) {
    n = glm::normalize(n);
    return Plane{n, -glm::dot(n, point)};
  };
  Frustum fr;
  fr.planes[0] = make(rt + tx * fw, eye);
  fr.planes[1] = make(-rt + tx * fw, eye);
  fr.planes[2] = make(up_v + ty * fw, eye);
  fr.planes[3] = make(-up_v + ty * fw, eye);
  fr.planes[4] = make(fw, eye + fw * near_dist);
  fr.planes[5] = make(-fw, eye + fw * far_dist);
  fr.cuts = sections.planes;
  fr.cut_count = sections.count;
  fr.eye = eye;
  return fr;
}

std::optional<std::string> Camera::invalid_reason() const {
  auto finite3 = [](const glm::dvec3& v) {
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
  };
  if (!finite3(eye)) return "non-finite eye position";
  if (!(std::isfinite(orientation.w) && std::isfinite(orientation.x) &&
        std::isfinite(orientation.y) && std::isfinite(orientation.z)))
    return "non-finite orientation";
  double qn = glm::length(orientation);
  if (!(std::abs(qn - 1.0) < 1e-6)) return "orientation is not a unit quaternion";
  if (!std::isfinite(fovy_rad) || !(fovy_rad > 0) || !(fovy_rad < glm::pi<double>()))
    return "fovy outside (0, 180) degrees";
  if (!std::isfinite(aspect) || !(aspect > 0)) return "aspect <= 0 or non-finite";
  if (!std::isfinite(near_dist) || !(near_dist > 0)) return "near <= 0 or non-finite";
  if (!std::isfinite(far_dist) || !(far_dist > near_dist)) return "far <= near or non-finite";
  return std::nullopt;
}

}  // namespace occ
