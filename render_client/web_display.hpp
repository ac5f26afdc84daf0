// render_client --web as the viewer's display (frame_display.hpp): frames go to the web server's
// pages (web_server.hpp), the drive pages' input comes back as window events.
//
// Each frame is one binary WebSocket message: a little-endian u32 N, N bytes of JSON (format,
// frame index, the camera as a --path CSV row, the HUD's numbers, the newest input it includes),
// then the image. While the camera changes from one frame to the next the image is JPEG; the
// first frame whose camera equals the one before while the user steers nothing (no drag, no
// movement key held) is sent as PNG (lossless: pixel for pixel the rendered frame). Other frames
// with the camera of the frame before are not sent at all.
#pragma once
#include <memory>

#include "common/web_input.hpp"
#include "render_client/frame_display.hpp"
#include "render_client/options.hpp"

namespace occ {

// Starts the server (throws InputError naming --web or --web's tls=) and prints its URLs.
std::unique_ptr<FrameDisplay> make_web_display(const ClientOptions& o);

// The window event the viewer handles for a page's input (a wheel of N notches: one event of
// button 4 or 5, repeated N times by the caller; blur: focus_out; quit: close), with its seq.
WindowEvent to_window_event(const WebInput& in);

// The JSON header of a frame message (web_display.hpp) for `f`, image `format`, encode time, and
// input_ms: the render client's share of the latency, from the arrival of input f.input_seq to
// this frame encoded (-1: the frame brings no new input).
std::string web_frame_header(const ShownFrame& f, const char* format, int width, int height, double encode_ms,
                             double input_ms);

}  // namespace occ
