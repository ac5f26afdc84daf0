// CPU time of the whole process (every thread: llvmpipe's rasteriser threads, the transport's
// I/O thread), for per-stage costs that do not depend on how many processes share the cores.
#pragma once
#include <chrono>
#include <cstdint>
#include <ctime>

namespace occ {

// Microseconds of CPU time this process has used since it started (CLOCK_PROCESS_CPUTIME_ID).
inline uint64_t process_cpu_us() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return uint64_t(ts.tv_sec) * 1000000u + uint64_t(ts.tv_nsec) / 1000u;
}

// When this process's static objects were made (before main: its start, near enough), and the
// seconds since.
inline const std::chrono::steady_clock::time_point kProcessStart = std::chrono::steady_clock::now();
inline double process_age_s() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - kProcessStart).count();
}

}  // namespace occ
