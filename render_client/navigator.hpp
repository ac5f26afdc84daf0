// Interactive camera control for render_client --window, without GL or X: keys, mouse drags and
// the wheel in, a Camera out. The window (window.hpp) translates X events into these calls; the
// unit tests drive it directly (tests/navigator_test.cpp).
//
// State: eye, yaw (about world +Y) and pitch (clamped to +-89 degrees), so the horizon stays level
// (no roll). Fly: W/S move along the view direction, A/D strafe, Q/E down/up (world Y). Walk: W/S
// and A/D move in the horizontal plane only, so the eye height stays fixed however the user looks;
// Q/E still change it on purpose. Speed: a fraction of the scene diagonal per second (the wheel
// scales it, Shift x5). A held key moves for as long as it is held (advance()); its first press
// also moves one tap step at once, so a short tap always moves even when press and release arrive
// together. Near and far follow the eye (auto_near_far), as for generated paths.
#pragma once
#include <cstdint>

#include "common/camera.hpp"
#include "common/math.hpp"

namespace occ {

enum class NavKey { forward, back, left, right, down, up, look_left, look_right, look_up, look_down, fast, count };

class Navigator {
 public:
  static constexpr double kTapSeconds = 0.1;       // a tap moves/turns as much as holding for this long
  static constexpr double kTurnDegPerSecond = 90;  // arrow keys
  static constexpr double kDragDegPerPixel = 0.25; // mouse drag
  static constexpr double kFastFactor = 5;         // Shift
  static constexpr double kWheelFactor = 1.25;     // per wheel notch

  // `home`: the camera R returns to (its fovy and aspect are kept); bounds: the scene's.
  Navigator(const Camera& home, const Aabb& bounds);

  void press(NavKey k);    // a repeated press while held (key auto-repeat) does nothing
  void release(NavKey k);
  void release_all();      // focus lost
  bool held(NavKey k) const { return held_[int(k)]; }
  bool moving() const;     // a movement or look key is held
  void advance(double seconds);  // moves by what is held
  void drag(double dx_px, double dy_px);  // right/down drag: look right/down
  void wheel(int notches);       // + faster, - slower
  void toggle_walk() { walk_ = !walk_; ++changes_; }
  bool walking() const { return walk_; }
  void reset();                  // back to home, fly mode, default speed
  void jump_to(const Camera& c); // follow a played path (the user can take over from there)

  Camera camera() const;
  double speed() const { return speed_; }  // world units per second, without Shift
  double yaw_deg() const { return yaw_; }
  double pitch_deg() const { return pitch_; }
  // Increases whenever the camera may have changed (to know whether a new frame is needed).
  uint64_t changes() const { return changes_; }

 private:
  void set_from(const Camera& c);
  void step(double seconds);  // what is held, for `seconds`
  void move(NavKey k, double seconds);
  glm::dvec3 forward() const;

  Camera home_;
  Aabb bounds_;
  double base_speed_;
  glm::dvec3 eye_{0.0};
  double yaw_ = 0, pitch_ = 0;  // degrees; yaw 0 looks down -Z, positive turns left (towards -X)
  double speed_;
  bool walk_ = false;
  bool held_[int(NavKey::count)] = {};
  uint64_t changes_ = 0;
};

}  // namespace occ
