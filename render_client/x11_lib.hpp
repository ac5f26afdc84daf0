// Xlib, loaded when --window first asks for it (dlopen): render_client links no X11 library, so
// it starts on a machine without one (a GPU node); without it, --window fails with one error
// naming libX11. $OCC_X11_LIBRARY names another file (one that does not exist makes Xlib
// unloadable: tests). Header-only, so the window test sends its events through the same table.
// Include it last: Xlib's macros (None, Bool, Status, ...) break headers that follow.
#pragma once
#include <X11/XKBlib.h>
#include <X11/Xatom.h>
#include <X11/Xlib.h>
#include <X11/Xutil.h>

#include "common/gl/dynamic_library.hpp"

// The Xlib functions render_client/window.cpp and tests/window_test.cpp call (the rest of what
// they use, DefaultScreen, BlackPixel, XPutPixel, XDestroyImage, ..., are macros over the
// Display and XImage structures).
#define OCC_X11_FUNCTIONS(X)                                                                    \
  X(XOpenDisplay) X(XCloseDisplay) X(XSetErrorHandler) X(XGetErrorText) X(XCreateSimpleWindow)  \
  X(XDestroyWindow) X(XSelectInput) X(XStoreName) X(XChangeProperty) X(XInternAtom)             \
  X(XSetClassHint) X(XAllocSizeHints) X(XSetWMNormalHints) X(XFree) X(XSetWMProtocols)          \
  X(XkbSetDetectableAutoRepeat) X(XCreateGC) X(XFreeGC) X(XCreateImage) X(XMapWindow) X(XFlush) \
  X(XSync) X(XPutImage) X(XSetForeground) X(XFillRectangle) X(XDrawString) X(XPending)          \
  X(XNextEvent) X(XLookupKeysym) X(XSendEvent)

namespace occ {

struct X11Lib {
  DynamicLibrary lib{"Xlib", "libX11.so.6", "OCC_X11_LIBRARY",
                     "--window needs libX11 (Debian: libx11-6); leave out --window and write frames with --out"};
#define OCC_X11_ENTRY(fn) decltype(&::fn) fn = lib.symbol<decltype(&::fn)>(#fn);
  OCC_X11_FUNCTIONS(OCC_X11_ENTRY)
#undef OCC_X11_ENTRY
};

// Loads Xlib on the first call; throws std::runtime_error naming the library until it loads.
inline const X11Lib& x11() {
  static const X11Lib lib;
  return lib;
}

}  // namespace occ
