// Progress on long work: a self-updating line on a terminal; on a pipe or log file, nothing
// (the summaries say what happened).
#pragma once
#include <unistd.h>

#include <cstdio>

namespace occ {

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
