// Cache files' places and temporaries (cache_files.hpp).
#include "common/cache_files.hpp"

#include <fcntl.h>
#include <signal.h>
#include <sys/file.h>
#include <unistd.h>

#include <cctype>
#include <cerrno>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <iostream>

#include "common/hash.hpp"

namespace occ {

namespace {

// This process's host and pid namespace as a temporary names them: "<host>.<namespace inode>",
// the host name's characters other than letters, digits and '-' written as '-'.
const std::string& writer_place() {
  static const std::string place = [] {
    char host[256] = {};
    ::gethostname(host, sizeof host - 1);
    std::string h = host;
    for (char& c : h)
      if (!std::isalnum(static_cast<unsigned char>(c)) && c != '-') c = '-';
    std::error_code ec;
    const std::string ns = std::filesystem::read_symlink("/proc/self/ns/pid", ec).string();  // "pid:[N]"
    std::string inode;
    for (char c : ns)
      if (std::isdigit(static_cast<unsigned char>(c))) inode += c;
    return (h.empty() ? "host" : h) + "." + (inode.empty() ? "0" : inode);
  }();
  return place;
}

bool ends_with(const std::string& s, const char* suffix) {
  const size_t n = std::strlen(suffix);
  return s.size() >= n && s.compare(s.size() - n, n, suffix) == 0;
}

// Whether the writer of temporary `name` (a file name) is gone; false for names of other files.
bool writer_gone(const std::string& name, const std::filesystem::path& file) {
  const size_t at = name.rfind(".tmp.");
  if (at == std::string::npos) return false;
  const std::string stem = name.substr(0, at), writer = name.substr(at + 5);
  if (!ends_with(stem, ".lod") && !ends_with(stem, ".scene")) return false;
  const size_t dot = writer.rfind('.');
  if (dot != std::string::npos && writer.compare(0, dot, writer_place()) == 0) {  // a writer here: ask it
    char* end = nullptr;
    const long pid = std::strtol(writer.c_str() + dot + 1, &end, 10);
    if (*end == '\0' && pid > 0 && pid != ::getpid() && ::kill(pid_t(pid), 0) != 0 && errno == ESRCH) return true;
  }
  // Any writer (also one whose pid another process now has): gone when the file has not changed
  // for long (a live writer writes on).
  std::error_code ec;
  const auto written = std::filesystem::last_write_time(file, ec);
  return !ec && std::filesystem::file_time_type::clock::now() - written > std::chrono::seconds(kStaleTempSeconds);
}

}  // namespace

std::string cache_temp_path(const std::string& path, long pid) {
  return path + ".tmp." + writer_place() + "." + std::to_string(pid < 0 ? long(::getpid()) : pid);
}

CacheBuildLock::CacheBuildLock(const std::string& path, const std::string& who) {
  std::error_code ec;
  const std::filesystem::path p(path);
  if (p.has_parent_path()) std::filesystem::create_directories(p.parent_path(), ec);
  fd_ = ::open((path + ".lock").c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  if (fd_ < 0) return;
  if (::flock(fd_, LOCK_EX | LOCK_NB) == 0) return;
  std::cerr << who << ": waiting for another process that builds " << path << "\n";
  while (::flock(fd_, LOCK_EX) != 0 && errno == EINTR) {
  }
}

CacheBuildLock::~CacheBuildLock() {
  if (fd_ >= 0) ::close(fd_);  // releases the flock
}

size_t remove_stale_cache_temps(const std::string& dir) {
  size_t removed = 0;
  std::error_code ec;
  for (std::filesystem::directory_iterator it(dir.empty() ? "." : dir, ec), end; !ec && it != end; it.increment(ec)) {
    std::error_code rm;
    if (writer_gone(it->path().filename().string(), it->path()) && std::filesystem::remove(it->path(), rm)) ++removed;
  }
  return removed;
}

std::string lod_cache_path(const std::string& cache_dir, const std::string& spec) {
  std::string dir = cache_dir;
  if (dir.empty()) {
    if (const char* x = std::getenv("XDG_CACHE_HOME"); x && *x)
      dir = std::string(x) + "/occswitch";
    else if (const char* home = std::getenv("HOME"); home && *home)
      dir = std::string(home) + "/.cache/occswitch";
    else
      dir = "/tmp/occswitch";
  }
  std::string name = std::filesystem::path(spec).filename().string();
  for (char& c : name)
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '.' && c != '-' && c != '_') c = '_';
  if (name.size() > 48) name.resize(48);
  Hasher hs;
  hs.str(spec);
  return dir + "/" + name + "-" + hex(hs.value() >> 32, 8).substr(2) + ".lod";  // top 8 hex digits
}

}  // namespace occ
