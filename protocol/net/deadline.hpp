// Bounded waits of the transport and the handshake (their .cpp files only).
#pragma once
#include <algorithm>
#include <chrono>

namespace occ::net {

// Longer waits are clamped (condition_variable::wait_for overflows near Millis::max()).
inline constexpr std::chrono::milliseconds kMaxWait = std::chrono::hours(24 * 365);

inline std::chrono::steady_clock::time_point deadline_after(std::chrono::milliseconds timeout) {
  return std::chrono::steady_clock::now() + std::clamp(timeout, std::chrono::milliseconds(0), kMaxWait);
}

inline std::chrono::milliseconds remaining_until(std::chrono::steady_clock::time_point deadline) {
  return std::max(std::chrono::milliseconds(0), std::chrono::duration_cast<std::chrono::milliseconds>(
                                                     deadline - std::chrono::steady_clock::now()));
}

}  // namespace occ::net
