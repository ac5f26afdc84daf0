#include "common/web_input.hpp"

#include <charconv>
#include <vector>

namespace occ {

namespace {

struct KeyName {
  const char* name;
  WebKey key;
};
constexpr KeyName kKeys[] = {{"w", WebKey::w},       {"a", WebKey::a},         {"s", WebKey::s},
                             {"d", WebKey::d},       {"q", WebKey::q},         {"e", WebKey::e},
                             {"f", WebKey::f},       {"r", WebKey::r},         {"p", WebKey::p},
                             {"o", WebKey::o},         {"up", WebKey::up},
                             {"down", WebKey::down}, {"left", WebKey::left},   {"right", WebKey::right},
                             {"shift", WebKey::shift}};

struct Kind {
  const char* name;
  WebInput::Kind kind;
  size_t args;
};
constexpr Kind kKinds[] = {{"kd", WebInput::Kind::key_down, 1},    {"ku", WebInput::Kind::key_up, 1},
                           {"bd", WebInput::Kind::button_down, 3}, {"bu", WebInput::Kind::button_up, 3},
                           {"mv", WebInput::Kind::motion, 2},      {"wh", WebInput::Kind::wheel, 1},
                           {"blur", WebInput::Kind::blur, 0},      {"quit", WebInput::Kind::quit, 0},
                           {"ping", WebInput::Kind::ping, 0}};

// Words separated by single spaces; empty words (leading, trailing or double spaces) fail.
bool split(std::string_view s, std::vector<std::string_view>& out) {
  size_t start = 0;
  for (size_t i = 0; i <= s.size(); ++i) {
    if (i < s.size() && s[i] != ' ') continue;
    if (i == start || out.size() == 6) return false;
    out.push_back(s.substr(start, i - start));
    start = i + 1;
  }
  return true;
}

// A decimal integer in [lo, hi]: an optional '-' then digits, nothing else.
bool integer(std::string_view w, long lo, long hi, long* v) {
  if (w.empty() || w.size() > 11) return false;
  const char* end = w.data() + w.size();
  auto r = std::from_chars(w.data(), end, *v);
  return r.ec == std::errc() && r.ptr == end && *v >= lo && *v <= hi && !(w.size() > 1 && w[0] == '+');
}

std::string bad(const char* what, std::string_view word) {
  std::string w;
  for (char c : word.substr(0, 16)) w += (c >= 0x20 && c < 0x7f) ? c : '?';
  return std::string(what) + " '" + w + "'";
}

}  // namespace

std::variant<WebInput, std::string> parse_web_input(std::string_view msg) {
  if (msg.size() > kMaxInputBytes) return "input message longer than " + std::to_string(kMaxInputBytes) + " bytes";
  std::vector<std::string_view> w;
  if (!split(msg, w) || w.size() < 2) return std::string("input message not 'SEQ KIND ARGS' (single spaces)");
  WebInput in;
  long v = 0;
  if (!integer(w[0], 1, 0x7fffffff, &v)) return bad("input sequence number", w[0]);
  in.seq = uint32_t(v);
  const Kind* kind = nullptr;
  for (const Kind& k : kKinds)
    if (w[1] == k.name) kind = &k;
  if (!kind) return bad("input kind", w[1]);
  if (w.size() != 2 + kind->args) return bad("wrong number of arguments for input kind", w[1]);
  in.kind = kind->kind;
  using K = WebInput::Kind;
  if (in.kind == K::key_down || in.kind == K::key_up) {
    for (const KeyName& k : kKeys)
      if (w[2] == k.name) in.key = k.key;
    if (in.key == WebKey::none) return bad("key", w[2]);
  } else if (in.kind == K::wheel) {
    if (!integer(w[2], -100, 100, &v) || v == 0) return bad("wheel notches", w[2]);
    in.notches = int(v);
  } else if (kind->args > 0) {
    const size_t xy = in.kind == K::motion ? 2 : 3;
    if (xy == 3) {
      if (!integer(w[2], 1, 3, &v)) return bad("button", w[2]);
      in.button = int(v);
    }
    if (!integer(w[xy], -100000, 100000, &v)) return bad("x", w[xy]);
    in.x = int(v);
    if (!integer(w[xy + 1], -100000, 100000, &v)) return bad("y", w[xy + 1]);
    in.y = int(v);
  }
  return in;
}

std::string format_web_input(const WebInput& in) {
  std::string s = std::to_string(in.seq) + " ";
  size_t args = 0;
  for (const Kind& k : kKinds)
    if (k.kind == in.kind) s += k.name, args = k.args;
  using K = WebInput::Kind;
  auto num = [&](int v) { s += " " + std::to_string(v); };
  if (in.kind == K::key_down || in.kind == K::key_up) {
    for (const KeyName& k : kKeys)
      if (k.key == in.key) s += std::string(" ") + k.name;
  } else if (in.kind == K::wheel) {
    num(in.notches);
  } else if (args > 0) {
    if (in.kind != K::motion) num(in.button);
    num(in.x);
    num(in.y);
  }
  return s;
}

}  // namespace occ
