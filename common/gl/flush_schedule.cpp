#include "common/gl/flush_schedule.hpp"

#include <cerrno>
#include <cstdlib>
#include <stdexcept>
#include <string>

namespace occ {
namespace {

// OCC_FLUSH_TRIANGLES as a part size; nullopt if unset.
std::optional<uint32_t> part_from_environment() {
  const char* v = std::getenv("OCC_FLUSH_TRIANGLES");
  if (!v || !*v) return std::nullopt;
  char* end = nullptr;
  errno = 0;
  const unsigned long long n = std::strtoull(v, &end, 10);
  if (*v < '0' || *v > '9' || *end || errno || n > 0xffffffffull)
    throw std::runtime_error(std::string("OCC_FLUSH_TRIANGLES=") + v +
                             ": not a triangle count (a whole number, 0 turns the flushes off)");
  return uint32_t(n);
}

}  // namespace

FlushSchedule FlushSchedule::from_environment() {
  static const FlushSchedule configured = [] {  // once a process
    FlushSchedule s;
    if (const std::optional<uint32_t> n = part_from_environment()) {
      s.fixed_ = *n;
      s.pinned_ = true;
    }
    return s;
  }();
  return configured;
}

}  // namespace occ
