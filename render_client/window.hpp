// A plain X11 window (Xlib) that shows finished RGBA frames with XPutImage and a one-line HUD
// strip under the image (XDrawString, the server's default font), and reports key, mouse and
// close events. Rendering stays offscreen (GlContext); the window only displays pixels, so it
// works on any X server (Xvfb, a remote display, a desktop) with no GL/window-system coupling.
// Xlib is loaded when the first window opens (x11_lib.hpp): render_client starts without it.
// Every call must come from one thread (the viewer's window thread, viewer.hpp).
#pragma once
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "common/image.hpp"

namespace occ {

enum class WinKey { w, a, s, d, q, e, f, r, p, o, up, down, left, right, shift, escape, other };

struct WindowEvent {
  enum class Type { key_down, key_up, button_down, button_up, motion, close, focus_out };
  Type type;
  WinKey key = WinKey::other;  // key_down, key_up
  int button = 0;              // button_down, button_up: 1 left, 2 middle, 3 right, 4/5 wheel
  int x = 0, y = 0;            // pointer position (buttons, motion)
  uint32_t seq = 0;            // --web: the page's input number (web_input.hpp); 0 from X
};

class X11Window {
 public:
  // Opens $DISPLAY and maps a width x (height + HUD strip) window titled `title` (UTF-8).
  // Throws std::runtime_error naming the display when there is none or it cannot be opened, and
  // "--window: cannot load Xlib libX11.so.6: ..." when Xlib is missing.
  static std::unique_ptr<X11Window> open(const std::string& title, int width, int height);
  ~X11Window();
  X11Window(const X11Window&) = delete;
  X11Window& operator=(const X11Window&) = delete;

  // Shows a frame (the viewport's size) and the HUD line under it.
  void show(const Image& img, const std::string& hud);
  // Redraws the last frame (after an Expose).
  void redraw();
  // Waits up to timeout_ms for X events or for `wake_fd` to become readable, then returns every
  // pending event.
  std::vector<WindowEvent> poll(int timeout_ms, int wake_fd);

 private:
  struct Impl;
  explicit X11Window(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace occ
