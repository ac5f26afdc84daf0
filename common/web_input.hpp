// The input messages a browser page sends to render_client --web over its WebSocket, and their
// parser: no GL, no sockets, no window, so the fuzz harness (common/fuzz) and the unit tests call
// it with bytes (render_client/web_display.hpp turns them into the viewer's window events).
// One text message is one event, ASCII words separated by single spaces:
//   SEQ kd KEY | SEQ ku KEY        key down / up; KEY: w a s d q e f r p o up down left right shift
//   SEQ bd B X Y | SEQ bu B X Y    button B (1 left, 2 middle, 3 right) down / up at pixel X, Y
//   SEQ mv X Y                     pointer (mouse or one finger) at X, Y
//   SEQ wh N                       wheel or pinch: N notches, + faster, - slower (N != 0)
//   SEQ blur                       the page lost focus: every key released
//   SEQ quit                       stop render_client (as the window's close button)
//   SEQ ping                       the page measures its round trip: the server answers with the
//                                  text message {"pong":SEQ} (not an event of the viewer)
// SEQ: the page's event number, 1 .. 2^31 - 1, for the latency it measures (event to the frame
// whose camera includes it). X, Y: -100000 .. 100000, N: -100 .. 100. At most kMaxInputBytes.
#pragma once
#include <cstdint>
#include <string>
#include <string_view>
#include <variant>


namespace occ {

inline constexpr size_t kMaxInputBytes = 64;

enum class WebKey { none, w, a, s, d, q, e, f, r, p, o, up, down, left, right, shift };

struct WebInput {
  enum class Kind { key_down, key_up, button_down, button_up, motion, wheel, blur, quit, ping };
  uint32_t seq = 0;
  Kind kind = Kind::blur;
  WebKey key = WebKey::none;   // key_down, key_up: never none
  int button = 0;              // button_down, button_up: 1..3
  int x = 0, y = 0;            // buttons, motion
  int notches = 0;             // wheel

  bool operator==(const WebInput&) const = default;
};

// Parses one message. Returns the event, or a non-empty one-line reason naming the first
// offending word (never throws for any bytes).
std::variant<WebInput, std::string> parse_web_input(std::string_view msg);
// The message parse_web_input reads back as `in` (in must be in range).
std::string format_web_input(const WebInput& in);
}  // namespace occ
