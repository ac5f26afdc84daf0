// render_client --window or --web: the display (frame_display.hpp: the X11 window of window.hpp, or
// the web pages of web_display.hpp) on a thread of its own, the user's camera
// (navigator.hpp), path playback with take-over, screenshots and OUT/path.csv. The renderer thread
// (client.cpp or reference.cpp) only asks for the next camera and hands over finished frames, so
// the window keeps handling events while a frame is in flight.
//
// Keys: W/A/S/D/Q/E move, arrows (or a left-button drag) look, Shift faster, wheel speed, F walk/fly,
// R reset, P screenshot (OUT/screenshot_NNNN.png, NNNN = the frame's number in the recording and
// in --out), O culling overlay (cluster: the boxes of the leaves in the frustum that occlusion
// culling removed, tinted orange over the frame; the HUD counts them), Esc or the close button quits.
// With a --path the path plays; any movement key, drag or R takes over (the run then goes on
// until the user quits). With no --path (or --path interactive) the user drives from the start
// of walk:1. While nothing moves, the reference renderer draws a new frame at most every 100 ms;
// the cluster keeps going at full rate (one camera per frame shown, as latest mode does).
#pragma once
#include <condition_variable>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "common/camera.hpp"
#include "common/image.hpp"
#include "render_client/navigator.hpp"
#include "render_client/options.hpp"
#include "render_client/frame_display.hpp"

namespace occ {

class Viewer {
 public:
  // Opens the window titled "occswitch — SCENE" (throws naming the display when there is none)
  // or starts the web server (--web), and checks OUT/path.csv is writable: call before the scene loads.
  explicit Viewer(const ClientOptions& o);
  ~Viewer();  // finish() if not done (errors are printed, not thrown)
  Viewer(const Viewer&) = delete;
  Viewer& operator=(const Viewer&) = delete;

  // Once the scene is loaded: loads the path to play (o.path unless interactive) and starts the
  // window thread. Throws InputError for a bad path.
  void start(const Aabb& bounds, const Viewport& vp);
  // Appends camera number cameras.size() to `cameras` (numbers are sequential): the path's
  // until the user takes over, then the user's. False when there is none (the path ended or the
  // user quit). Reference renderer: while nothing moves, waits up to 100 ms for the user first.
  bool next_camera(std::vector<Camera>& cameras);
  // A frame was rendered with `cam`: show it, record the camera.
  void show(const Camera& cam, Image img, const HudStats& hud);
  bool quit() const;
  // The culling overlay is on (O): tint the occlusion-culled boxes into the image given to show().
  bool overlay() const;
  // Stops the window thread and writes OUT/path.csv. Throws InputError when the file cannot be written.
  void finish();

 private:
  void run_window();
  void handle(const WindowEvent& ev);
  std::string hud_line(const HudStats& h) const;
  double fps() const;  // frames shown in the last second

  const ClientOptions& o_;
  std::unique_ptr<FrameDisplay> display_;
  std::unique_ptr<Navigator> nav_;
  std::vector<Camera> path_;
  bool interactive_ = false;
  int wake_[2] = {-1, -1};  // pipe: a frame is ready / stop
  std::thread thread_;

  mutable std::mutex mu_;
  std::condition_variable changed_;
  bool stop_ = false, quit_ = false, taken_over_ = false, overlay_ = false, finished_ = false;
  bool screenshot_ = false, dragging_ = false;
  int drag_x_ = 0, drag_y_ = 0;
  uint64_t sent_changes_ = ~uint64_t(0);
  std::vector<Camera> recorded_;  // every camera shown, in order
  std::shared_ptr<const Image> pending_;  // to show next (with pending_frame_)
  ShownFrame pending_frame_;
  uint32_t input_seq_ = 0;             // the newest input event handled (WindowEvent::seq)
  std::vector<uint32_t> camera_seq_;   // per camera number: input_seq_ when it was taken
  uint32_t pending_index_ = 0;
  std::shared_ptr<const Image> displayed_;
  uint32_t displayed_index_ = 0;
  std::vector<double> show_times_ms_;  // for fps: the last second
  std::string message_;                // shown in the HUD for a moment (screenshot written, ...)
  double message_until_ms_ = 0;
};

}  // namespace occ
