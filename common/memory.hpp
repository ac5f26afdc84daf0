// The process's own peak resident memory, for summary lines (peak_rss_mb=N).
#pragma once
#include <cstdio>
#include <cstdlib>
#include <cstring>

namespace occ {

// A field of /proc/self/status ("VmHWM:", "VmRSS:") in MiB (rounded up), or -1.
inline long status_mb(const char* field) {
  std::FILE* f = std::fopen("/proc/self/status", "r");
  if (!f) return -1;
  char line[256];
  long kb = -1;
  while (std::fgets(line, sizeof line, f))
    if (std::strncmp(line, field, std::strlen(field)) == 0) {
      kb = std::strtol(line + std::strlen(field), nullptr, 10);
      break;
    }
  std::fclose(f);
  return kb < 0 ? -1 : (kb + 1023) / 1024;
}

// VmHWM (peak resident memory) in MiB (rounded up), or -1 where it cannot be read.
inline long peak_rss_mb() { return status_mb("VmHWM:"); }
// VmRSS (resident memory now) in MiB (rounded up), or -1.
inline long rss_mb() { return status_mb("VmRSS:"); }

}  // namespace occ
