// CPU time of the whole process (every thread: llvmpipe's rasteriser threads, the transport's
// I/O thread), for per-stage costs that do not depend on how many processes share the cores.
#pragma once
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstring>
#include <ctime>

namespace occ {

// Microseconds of CPU time this process has used since it started (CLOCK_PROCESS_CPUTIME_ID).
inline uint64_t process_cpu_us() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return uint64_t(ts.tv_sec) * 1000000u + uint64_t(ts.tv_nsec) / 1000u;
}

// Seconds since this process started (its start time in /proc/self/stat against
// CLOCK_BOOTTIME), or -1 where that cannot be read.
inline double process_age_s() {
  std::FILE* f = std::fopen("/proc/self/stat", "r");
  if (!f) return -1;
  char buf[1024] = {};
  const size_t n = std::fread(buf, 1, sizeof buf - 1, f);
  std::fclose(f);
  const char* p = std::strrchr(buf, ')');  // the command name may hold spaces
  if (n == 0 || !p) return -1;
  unsigned long long start = 0;
  int field = 2;  // ")" ends field 2; starttime is field 22
  for (++p; *p && field < 21; ++p)
    if (*p == ' ') ++field;
  if (std::sscanf(p, "%llu", &start) != 1) return -1;
  timespec now{};
  clock_gettime(CLOCK_BOOTTIME, &now);
  return double(now.tv_sec) + now.tv_nsec / 1e9 - double(start) / double(::sysconf(_SC_CLK_TCK));
}

}  // namespace occ
