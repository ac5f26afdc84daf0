// The process's own peak resident memory, for summary lines (peak_rss_mb=N), and huge pages for
// its heap.
#pragma once
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <optional>
#include <string>
#include <thread>
#include <utility>

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

// Transparent huge pages for large heap blocks (glibc's tunable glibc.malloc.hugetlb=1: malloc
// madvises its large mappings MADV_HUGEPAGE; this kernel's THP mode is "madvise"). The geometry
// the processes stage and llvmpipe's copy of it are large blocks written once, and with 4 KiB
// pages their page faults were a large part of start-up on paravirtualised machines (measured on
// plant:13; peak RSS unchanged). glibc reads tunables only
// when a process starts, so the process executes itself again, once, with the tunable added to
// GLIBC_TUNABLES (same pid, arguments and descriptors). OCC_HUGE_PAGES=0 turns this off; if the
// exec fails the process simply goes on with small pages. Call first thing in main().
inline void use_huge_pages(char** argv) {
  const char* off = std::getenv("OCC_HUGE_PAGES");
  if (off && std::strcmp(off, "0") == 0) return;
  const char* had = std::getenv("GLIBC_TUNABLES");
  std::string tunables = had ? had : "";
  if (tunables.find("glibc.malloc.hugetlb") != std::string::npos) return;  // set by the user, or done
  tunables += tunables.empty() ? "glibc.malloc.hugetlb=1" : ":glibc.malloc.hugetlb=1";
  if (::setenv("GLIBC_TUNABLES", tunables.c_str(), 1) != 0) return;
  ::execv("/proc/self/exe", argv);
  // Still here: exec failed (no /proc?). Leave the environment as it was.
  if (had) ::setenv("GLIBC_TUNABLES", had, 1); else ::unsetenv("GLIBC_TUNABLES");
}

// Returns fn() computed on a thread of its own (exceptions pass through). glibc gives a new
// thread a malloc arena of its own, so what fn allocates lives there, and so do the holes left when
// the scene's CPU geometry is freed as it is uploaded, between the names, boxes and indexes that
// stay. In the main arena those holes made every malloc of llvmpipe's 64 KiB binning blocks (its
// main thread allocates and frees thousands a second) search long free lists (perf showed
// _int_malloc high on a plant:13 process; with the load on its own thread it is negligible).
template <class F>
auto in_own_arena(F&& fn) -> decltype(fn()) {
  std::optional<decltype(fn())> result;
  std::exception_ptr error;
  std::thread([&] {
    try {
      result.emplace(fn());
    } catch (...) {
      error = std::current_exception();
    }
  }).join();
  if (error) std::rethrow_exception(error);
  return std::move(*result);
}

}  // namespace occ
