// Port files (transport.hpp): --port 0 / --port-file, written atomically, read with a bounded wait.
#include <unistd.h>

#include <algorithm>
#include <charconv>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <thread>

#include "protocol/net/transport.hpp"

namespace occ::net {

std::optional<std::string> write_port_file(const std::string& path, uint16_t port) {
  const std::string tmp = path + ".tmp." + std::to_string(::getpid());
  {
    std::ofstream out(tmp, std::ios::trunc);
    out << port << '\n';
    out.flush();
    if (!out) return "cannot write port file " + tmp;
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    std::remove(tmp.c_str());
    return "cannot rename " + tmp + " to " + path;
  }
  return std::nullopt;
}

Result<uint16_t> read_port_file(const std::string& path, Millis timeout) {
  using Clock = std::chrono::steady_clock;
  const Clock::time_point deadline =
      Clock::now() + std::clamp(timeout, Millis(0), Millis(std::chrono::hours(24 * 365)));  // no overflow
  auto remaining_until = [&](Clock::time_point d) {
    return std::max(Millis(0), std::chrono::duration_cast<Millis>(d - Clock::now()));
  };
  for (;;) {
    std::ifstream in(path);
    if (in) {
      std::string text;
      std::getline(in, text);
      unsigned value = 0;
      auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
      if (ec != std::errc() || end != text.data() + text.size() || value == 0 || value > 65535)
        return Error{"port file " + path + ": invalid content '" + text.substr(0, 32) + "'"};
      return static_cast<uint16_t>(value);
    }
    if (remaining_until(deadline) == Millis(0))
      return Error{"port file " + path + " did not appear within " +
                   std::to_string(timeout.count()) + " ms"};
    std::this_thread::sleep_for(std::min(remaining_until(deadline), Millis(10)));
  }
}

}  // namespace occ::net
