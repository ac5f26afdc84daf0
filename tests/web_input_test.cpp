// The input messages of render_client --web's page (common/web_input.hpp): what each kind
// reads as, the window event it becomes, and the messages that are refused with a reason.
#include <gtest/gtest.h>

#include "common/web_input.hpp"
#include "render_client/web_display.hpp"

using namespace occ;

namespace {

WebInput ok(const std::string& msg) {
  auto r = parse_web_input(msg);
  if (auto* why = std::get_if<std::string>(&r)) ADD_FAILURE() << msg << ": " << *why;
  return std::holds_alternative<WebInput>(r) ? std::get<WebInput>(r) : WebInput{};
}

std::string refused(const std::string& msg) {
  auto r = parse_web_input(msg);
  if (std::holds_alternative<WebInput>(r)) ADD_FAILURE() << "accepted: " << msg;
  return std::holds_alternative<std::string>(r) ? std::get<std::string>(r) : "";
}

TEST(WebInput, EveryKindReadsAsItsEvent) {
  EXPECT_EQ(ok("7 kd w"), (WebInput{7, WebInput::Kind::key_down, WebKey::w}));
  EXPECT_EQ(ok("8 ku shift").key, WebKey::shift);
  EXPECT_EQ(ok("9 bd 1 10 -20"), (WebInput{9, WebInput::Kind::button_down, WebKey::none, 1, 10, -20}));
  EXPECT_EQ(ok("10 mv 300 400"), (WebInput{10, WebInput::Kind::motion, WebKey::none, 0, 300, 400}));
  EXPECT_EQ(ok("11 wh -3").notches, -3);
  EXPECT_EQ(ok("12 blur").kind, WebInput::Kind::blur);
  EXPECT_EQ(ok("13 quit").kind, WebInput::Kind::quit);
  EXPECT_EQ(ok("14 ping").kind, WebInput::Kind::ping);
}

TEST(WebInput, FormattedMessagesReadBack) {
  for (const char* m : {"1 kd up", "2 bu 3 0 0", "3 mv -100000 100000", "4 wh 100", "5 blur", "6 quit", "7 ping"})
    EXPECT_EQ(format_web_input(ok(m)), m);
}

TEST(WebInput, WindowEventsCarryTheSequenceNumber) {
  const WindowEvent down = to_window_event(ok("5 bd 1 3 4"));
  EXPECT_EQ(down.type, WindowEvent::Type::button_down);
  EXPECT_EQ(down.button, 1);
  EXPECT_EQ(down.x, 3);
  EXPECT_EQ(down.seq, 5u);
  EXPECT_EQ(to_window_event(ok("6 wh 2")).button, 4);   // faster: the wheel up
  EXPECT_EQ(to_window_event(ok("7 wh -1")).button, 5);
  EXPECT_EQ(to_window_event(ok("8 blur")).type, WindowEvent::Type::focus_out);
  EXPECT_EQ(to_window_event(ok("9 quit")).type, WindowEvent::Type::close);
  EXPECT_EQ(to_window_event(ok("10 kd left")).key, WinKey::left);
}

TEST(WebInput, BadMessagesAreRefusedNamingTheWord) {
  EXPECT_EQ(refused("0 kd w"), "input sequence number '0'");
  EXPECT_EQ(refused("2147483648 kd w"), "input sequence number '2147483648'");
  EXPECT_EQ(refused("1 jump"), "input kind 'jump'");
  EXPECT_EQ(refused("1 kd z"), "key 'z'");
  EXPECT_EQ(refused("1 kd"), "wrong number of arguments for input kind 'kd'");
  EXPECT_EQ(refused("1 bd 4 0 0"), "button '4'");
  EXPECT_EQ(refused("1 mv 100001 0"), "x '100001'");
  EXPECT_EQ(refused("1 mv 0 1e3"), "y '1e3'");
  EXPECT_EQ(refused("1 wh 0"), "wheel notches '0'");
  EXPECT_EQ(refused("1 kd \x01"), "key '?'");
  EXPECT_FALSE(refused("1  kd w").empty());  // double space
  EXPECT_FALSE(refused(" 1 kd w").empty());
  EXPECT_FALSE(refused("1 kd w ").empty());
  EXPECT_FALSE(refused("").empty());
  EXPECT_FALSE(refused(std::string(kMaxInputBytes + 1, '1')).empty());
  EXPECT_FALSE(refused(std::string("1 kd w\0", 7)).empty());
}

}  // namespace
