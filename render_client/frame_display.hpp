// Where the viewer (viewer.hpp) shows frames and gets the user's input from: the X11 window
// (--window) or the pages of the web server (--web, web_display.hpp). Both are called from the
// viewer's window thread only.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "common/camera.hpp"
#include "common/image.hpp"
#include "render_client/window.hpp"

namespace occ {

// What the HUD line shows besides fps (the viewer measures that).
struct HudStats {
  double latency_ms = 0;   // camera sent -> frame shown (reference: render time)
  size_t visible = 0;      // |V|: leaves drawn
  size_t leaves = 0;       // leaves in the scene (culled % = 1 - visible / leaves)
  uint64_t triangles = 0;
  double tau = 0;          // pixel error
  long occluded = -1;      // culling overlay on: leaves tinted (in the frustum, occlusion-culled); -1 off
  // Cluster: how this frame was culled (client.cpp: switch, resync, single, frustum); shown in
  // front of the line unless it is the normal "switch". Empty for the reference renderer.
  std::string mode;
  uint32_t camera = 0;     // the camera's number (Viewer::next_camera's order)
};

// One frame as the viewer hands it over.
struct ShownFrame {
  std::string hud;         // the HUD line, as the window shows it
  HudStats stats;
  double fps = 0;          // frames shown in the last second
  double frame_ms = 0;     // since the frame shown before
  Camera camera;           // the camera it was rendered with
  uint32_t index = 0;      // its number among the frames shown (its row in OUT/path.csv)
  uint32_t input_seq = 0;  // the newest input event its camera includes (WindowEvent::seq; 0 none)
  bool steering = false;   // a drag or a movement key was in progress when it was shown
};

class FrameDisplay {
 public:
  virtual ~FrameDisplay() = default;
  virtual void show(const Image& img, const ShownFrame& frame) = 0;
  // Waits up to timeout_ms for input or for `wake_fd` to become readable (then drained), and
  // returns every input event pending.
  virtual std::vector<WindowEvent> poll(int timeout_ms, int wake_fd) = 0;
};

}  // namespace occ
