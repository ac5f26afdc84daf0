// Progress on long work: a self-updating line on a terminal; on a pipe or log file, nothing
// (the summaries say what happened). now_ms() times the work for ETAs and summaries.
#pragma once
#include <unistd.h>

#include <chrono>
#include <cstdio>

namespace occ {

// Milliseconds on the monotonic clock (differences only).
inline double now_ms() {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

template <class... Args>
void progress(const char* fmt, Args... args) {
  if (!isatty(STDERR_FILENO)) return;
  std::fputc('\r', stderr);
  std::fprintf(stderr, fmt, args...);
  std::fflush(stderr);
}

inline void progress_done() {
  if (isatty(STDERR_FILENO)) std::fputc('\n', stderr);
}

}  // namespace occ
