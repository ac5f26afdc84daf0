#include "render_client/window.hpp"

#include <X11/keysym.h>
#include <poll.h>
#include <unistd.h>

#include <atomic>
#include <bit>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <stdexcept>

#include "render_client/x11_lib.hpp"  // last: Xlib's macros

namespace occ {

namespace {
constexpr int kHudHeight = 16;

// The window destroyed under us (xdotool windowclose, a crashed window manager): Xlib's default
// handler would exit(1); this one ends the run like the close button.
std::atomic<bool> g_window_gone{false};
int on_x_error(Display* dpy, XErrorEvent* e) {
  const X11Lib& xl = x11();
  if (e->error_code == BadWindow || e->error_code == BadDrawable) {
    g_window_gone = true;
  } else {
    char text[256];
    xl.XGetErrorText(dpy, e->error_code, text, sizeof text);
    std::fprintf(stderr, "render_client: X error (ignored): %s (request %d)\n", text, int(e->request_code));
  }
  return 0;
}

int shift_of(unsigned long mask) { return mask ? std::countr_zero(mask) : 0; }

WinKey key_of(KeySym k) {
  switch (k) {
    case XK_w: case XK_W: return WinKey::w;
    case XK_a: case XK_A: return WinKey::a;
    case XK_s: case XK_S: return WinKey::s;
    case XK_d: case XK_D: return WinKey::d;
    case XK_q: case XK_Q: return WinKey::q;
    case XK_e: case XK_E: return WinKey::e;
    case XK_f: case XK_F: return WinKey::f;
    case XK_r: case XK_R: return WinKey::r;
    case XK_p: case XK_P: return WinKey::p;
    case XK_o: case XK_O: return WinKey::o;
    case XK_Up: case XK_KP_Up: return WinKey::up;
    case XK_Down: case XK_KP_Down: return WinKey::down;
    case XK_Left: case XK_KP_Left: return WinKey::left;
    case XK_Right: case XK_KP_Right: return WinKey::right;
    case XK_Shift_L: case XK_Shift_R: return WinKey::shift;
    case XK_Escape: return WinKey::escape;
    default: return WinKey::other;
  }
}
}  // namespace

struct X11Window::Impl {
  const X11Lib& xl = x11();
  Display* dpy = nullptr;
  ::Window win = 0;
  GC gc = nullptr;
  Atom wm_delete = 0;
  Visual* visual = nullptr;
  int depth = 0, width = 0, height = 0;
  XImage* ximage = nullptr;
  std::vector<char> pixels;  // the XImage's data (ours: detached before XDestroyImage)
  std::string hud;
  bool have_frame = false;

  ~Impl() {
    if (ximage) {
      ximage->data = nullptr;
      XDestroyImage(ximage);
    }
    if (gc) xl.XFreeGC(dpy, gc);
    if (win) xl.XDestroyWindow(dpy, win);
    if (dpy) xl.XCloseDisplay(dpy);
  }

  void paint() {
    if (g_window_gone) return;
    if (have_frame) xl.XPutImage(dpy, win, gc, ximage, 0, 0, 0, 0, unsigned(width), unsigned(height));
    xl.XSetForeground(dpy, gc, BlackPixel(dpy, DefaultScreen(dpy)));
    xl.XFillRectangle(dpy, win, gc, 0, height, unsigned(width), kHudHeight);
    xl.XSetForeground(dpy, gc, WhitePixel(dpy, DefaultScreen(dpy)));
    xl.XDrawString(dpy, win, gc, 3, height + kHudHeight - 4, hud.data(), int(hud.size()));
    xl.XFlush(dpy);
  }
};

X11Window::X11Window(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
X11Window::~X11Window() = default;

std::unique_ptr<X11Window> X11Window::open(const std::string& title, int width, int height) {
  const X11Lib& xl = []() -> const X11Lib& {  // one error naming libX11 when it is missing
    try {
      return x11();
    } catch (const std::runtime_error& e) {
      throw std::runtime_error(std::string("--window: ") + e.what());
    }
  }();
  const char* name = std::getenv("DISPLAY");
  if (!name || !*name)
    throw std::runtime_error("--window: DISPLAY is not set: no X server to show the window on (run under X, ssh -X, "
                             "or Xvfb; or leave out --window and write frames with --out)");
  auto impl = std::make_unique<Impl>();
  impl->dpy = xl.XOpenDisplay(name);
  if (!impl->dpy)
    throw std::runtime_error(std::string("--window: cannot open X display '") + name +
                             "' (no X server there, or not allowed to connect)");
  Display* dpy = impl->dpy;
  xl.XSetErrorHandler(on_x_error);
  const int screen = DefaultScreen(dpy);
  impl->visual = DefaultVisual(dpy, screen);
  impl->depth = DefaultDepth(dpy, screen);
  impl->width = width;
  impl->height = height;
  if (impl->visual->c_class != TrueColor && impl->visual->c_class != DirectColor)
    throw std::runtime_error(std::string("--window: display '") + name + "' has no true-colour default visual");
  impl->win = xl.XCreateSimpleWindow(dpy, RootWindow(dpy, screen), 0, 0, unsigned(width), unsigned(height + kHudHeight), 0,
                                  BlackPixel(dpy, screen), BlackPixel(dpy, screen));
  xl.XSelectInput(dpy, impl->win,
               KeyPressMask | KeyReleaseMask | ButtonPressMask | ButtonReleaseMask | PointerMotionMask | ExposureMask |
                   FocusChangeMask | StructureNotifyMask);
  // Title: ASCII WM_NAME for old window managers, UTF-8 _NET_WM_NAME for the others.
  std::string ascii;
  for (unsigned char c : title)
    if (c < 0x80) ascii += char(c);
    else if (c >= 0xC0) ascii += '-';  // one '-' per non-ASCII character (the em dash)
  xl.XStoreName(dpy, impl->win, ascii.c_str());
  xl.XChangeProperty(dpy, impl->win, xl.XInternAtom(dpy, "_NET_WM_NAME", False), xl.XInternAtom(dpy, "UTF8_STRING", False), 8,
                  PropModeReplace, reinterpret_cast<const unsigned char*>(title.data()), int(title.size()));
  XClassHint cls{const_cast<char*>("render_client"), const_cast<char*>("occswitch")};
  xl.XSetClassHint(dpy, impl->win, &cls);
  XSizeHints* hints = xl.XAllocSizeHints();
  hints->flags = PMinSize | PMaxSize;
  hints->min_width = hints->max_width = width;
  hints->min_height = hints->max_height = height + kHudHeight;
  xl.XSetWMNormalHints(dpy, impl->win, hints);
  xl.XFree(hints);
  impl->wm_delete = xl.XInternAtom(dpy, "WM_DELETE_WINDOW", False);
  xl.XSetWMProtocols(dpy, impl->win, &impl->wm_delete, 1);
  Bool supported = False;
  xl.XkbSetDetectableAutoRepeat(dpy, True, &supported);  // held keys: repeated presses, one release
  impl->gc = xl.XCreateGC(dpy, impl->win, 0, nullptr);
  impl->pixels.assign(size_t(width) * height * 4, 0);
  impl->ximage = xl.XCreateImage(dpy, impl->visual, unsigned(impl->depth), ZPixmap, 0, impl->pixels.data(),
                              unsigned(width), unsigned(height), 32, 0);
  if (!impl->ximage) throw std::runtime_error("--window: XCreateImage failed");
  xl.XMapWindow(dpy, impl->win);
  xl.XFlush(dpy);
  return std::unique_ptr<X11Window>(new X11Window(std::move(impl)));
}

void X11Window::show(const Image& img, const std::string& hud) {
  Impl& m = *impl_;
  if (img.width != m.width || img.height != m.height) throw std::logic_error("X11Window::show: wrong image size");
  XImage* xi = m.ximage;
  const int rs = shift_of(xi->red_mask), gs = shift_of(xi->green_mask), bs = shift_of(xi->blue_mask);
  const bool fast = xi->bits_per_pixel == 32 && xi->byte_order == (std::endian::native == std::endian::little ? LSBFirst : MSBFirst) &&
                    xi->red_mask == (0xffUL << rs) && xi->green_mask == (0xffUL << gs) && xi->blue_mask == (0xffUL << bs);
  const uint8_t* src = img.rgba.data();
  for (int y = 0; y < m.height; ++y) {
    uint32_t* row = reinterpret_cast<uint32_t*>(xi->data + size_t(y) * xi->bytes_per_line);
    for (int x = 0; x < m.width; ++x, src += 4) {
      if (fast) {
        row[x] = uint32_t(src[0]) << rs | uint32_t(src[1]) << gs | uint32_t(src[2]) << bs;
      } else {
        auto scale = [](uint8_t v, unsigned long mask) {
          const int s = shift_of(mask);
          const unsigned long max = mask >> s;
          return ((unsigned long)(v) * max / 255) << s;
        };
        XPutPixel(xi, x, y, scale(src[0], xi->red_mask) | scale(src[1], xi->green_mask) | scale(src[2], xi->blue_mask));
      }
    }
  }
  m.have_frame = true;
  m.hud = hud;
  m.paint();
}

void X11Window::redraw() { impl_->paint(); }

std::vector<WindowEvent> X11Window::poll(int timeout_ms, int wake_fd) {
  Impl& m = *impl_;
  const X11Lib& xl = m.xl;
  if (!xl.XPending(m.dpy)) {
    pollfd fds[2] = {{ConnectionNumber(m.dpy), POLLIN, 0}, {wake_fd, POLLIN, 0}};
    ::poll(fds, wake_fd >= 0 ? 2 : 1, timeout_ms);
    if (wake_fd >= 0 && (fds[1].revents & POLLIN)) {
      char buf[64];
      while (::read(wake_fd, buf, sizeof buf) == ssize_t(sizeof buf)) {
      }
    }
  }
  std::vector<WindowEvent> out;
  while (xl.XPending(m.dpy)) {
    XEvent ev;
    xl.XNextEvent(m.dpy, &ev);
    using T = WindowEvent::Type;
    switch (ev.type) {
      case KeyPress:
      case KeyRelease:
        out.push_back({ev.type == KeyPress ? T::key_down : T::key_up, key_of(xl.XLookupKeysym(&ev.xkey, 0)), 0, 0, 0});
        break;
      case ButtonPress:
      case ButtonRelease:
        out.push_back({ev.type == ButtonPress ? T::button_down : T::button_up, WinKey::other, int(ev.xbutton.button),
                       ev.xbutton.x, ev.xbutton.y});
        break;
      case MotionNotify:
        out.push_back({T::motion, WinKey::other, 0, ev.xmotion.x, ev.xmotion.y});
        break;
      case ClientMessage:
        if (Atom(ev.xclient.data.l[0]) == m.wm_delete) out.push_back({T::close});
        break;
      case DestroyNotify:
        out.push_back({T::close});
        break;
      case FocusOut:
        out.push_back({T::focus_out});
        break;
      case Expose:
        if (ev.xexpose.count == 0) m.paint();
        break;
      default:
        break;
    }
  }
  xl.XSync(m.dpy, False);  // errors of what this poll and the last show() sent arrive now
  if (g_window_gone) out.push_back({WindowEvent::Type::close});
  return out;
}

}  // namespace occ
