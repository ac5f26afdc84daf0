// The process's own peak resident memory, for summary lines (peak_rss_mb=N).
#pragma once
#include <cstdio>
#include <cstdlib>
#include <cstring>

namespace occ {

// VmHWM from /proc/self/status in MiB (rounded up), or -1 where it cannot be read.
inline long peak_rss_mb() {
  std::FILE* f = std::fopen("/proc/self/status", "r");
  if (!f) return -1;
  char line[256];
  long kb = -1;
  while (std::fgets(line, sizeof line, f))
    if (std::strncmp(line, "VmHWM:", 6) == 0) {
      kb = std::strtol(line + 6, nullptr, 10);
      break;
    }
  std::fclose(f);
  return kb < 0 ? -1 : (kb + 1023) / 1024;
}

}  // namespace occ
