#include "render_client/navigator.hpp"

#include <algorithm>
#include <cmath>

#include "common/camera_path.hpp"

namespace occ {

namespace {
constexpr double kMaxPitch = 89.0;
constexpr double kSpeedOfDiagonal = 0.03;  // per second
bool is_look(NavKey k) {
  return k == NavKey::look_left || k == NavKey::look_right || k == NavKey::look_up || k == NavKey::look_down;
}
}  // namespace

Navigator::Navigator(const Camera& home, const Aabb& bounds)
    : home_(home), bounds_(bounds), base_speed_(std::max(bounds.empty() ? 1.0 : bounds.diagonal(), 1e-6) * kSpeedOfDiagonal),
      speed_(base_speed_) {
  set_from(home);
}

void Navigator::set_from(const Camera& c) {
  eye_ = c.eye;
  const glm::dvec3 f = glm::normalize(c.forward());
  pitch_ = std::clamp(glm::degrees(std::asin(std::clamp(f.y, -1.0, 1.0))), -kMaxPitch, kMaxPitch);
  yaw_ = glm::degrees(std::atan2(-f.x, -f.z));
  ++changes_;
}

glm::dvec3 Navigator::forward() const {
  const double y = glm::radians(yaw_), p = glm::radians(pitch_);
  return {-std::sin(y) * std::cos(p), std::sin(p), -std::cos(y) * std::cos(p)};
}

Camera Navigator::camera() const {
  Camera c = Camera::look_at(eye_, eye_ + forward(), {0, 1, 0}, glm::degrees(home_.fovy_rad), home_.aspect,
                             home_.near_dist, home_.far_dist);
  if (!bounds_.empty()) auto_near_far(c, bounds_);
  return c;
}

void Navigator::press(NavKey k) {
  if (held_[int(k)]) return;  // auto-repeat
  held_[int(k)] = true;
  if (k != NavKey::fast) move(k, kTapSeconds);
}

void Navigator::release(NavKey k) { held_[int(k)] = false; }

void Navigator::release_all() {
  for (bool& h : held_) h = false;
}

bool Navigator::moving() const {
  for (int k = 0; k < int(NavKey::count); ++k)
    if (held_[k] && NavKey(k) != NavKey::fast) return true;
  return false;
}

void Navigator::advance(double seconds) {
  if (seconds <= 0) return;
  for (int k = 0; k < int(NavKey::count); ++k)
    if (held_[k] && NavKey(k) != NavKey::fast) move(NavKey(k), seconds);
}

void Navigator::move(NavKey k, double seconds) {
  if (is_look(k)) {
    const double deg = kTurnDegPerSecond * seconds;
    if (k == NavKey::look_left) yaw_ += deg;
    if (k == NavKey::look_right) yaw_ -= deg;
    if (k == NavKey::look_up) pitch_ = std::min(pitch_ + deg, kMaxPitch);
    if (k == NavKey::look_down) pitch_ = std::max(pitch_ - deg, -kMaxPitch);
    ++changes_;
    return;
  }
  const double dist = speed_ * (held_[int(NavKey::fast)] ? kFastFactor : 1.0) * seconds;
  const double y = glm::radians(yaw_);
  const glm::dvec3 right(std::cos(y), 0, -std::sin(y));
  glm::dvec3 fwd = forward();
  if (walk_) fwd = glm::dvec3(-std::sin(y), 0, -std::cos(y));
  switch (k) {
    case NavKey::forward: eye_ += fwd * dist; break;
    case NavKey::back: eye_ -= fwd * dist; break;
    case NavKey::right: eye_ += right * dist; break;
    case NavKey::left: eye_ -= right * dist; break;
    case NavKey::up: eye_.y += dist; break;
    case NavKey::down: eye_.y -= dist; break;
    default: return;
  }
  ++changes_;
}

void Navigator::drag(double dx_px, double dy_px) {
  if (dx_px == 0 && dy_px == 0) return;
  yaw_ -= dx_px * kDragDegPerPixel;
  pitch_ = std::clamp(pitch_ - dy_px * kDragDegPerPixel, -kMaxPitch, kMaxPitch);
  ++changes_;
}

void Navigator::wheel(int notches) {
  speed_ = std::clamp(speed_ * std::pow(kWheelFactor, notches), base_speed_ * 1e-4, base_speed_ * 1e4);
  ++changes_;
}

void Navigator::reset() {
  set_from(home_);
  speed_ = base_speed_;
  walk_ = false;
}

void Navigator::jump_to(const Camera& c) { set_from(c); }

}  // namespace occ
