// Read-only memory-mapped files for the binary caches (scene_cache.cpp, lod_cache.cpp), and the
// streaming payload hash both caches check. No GL.
//
// A cache is parsed straight from the mapping (no read into a buffer of the file's size), and
// the pages already parsed are dropped from the process as it goes (drop_before): the page cache
// keeps them for the next process, but they no longer count in this one's resident memory, so
// loading a cache costs about the data it yields, not the data plus the file.
#pragma once
#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <optional>
#include <string>

#include "common/hash.hpp"

namespace occ {

class MappedFile {
 public:
  MappedFile() = default;
  MappedFile(const MappedFile&) = delete;
  MappedFile& operator=(const MappedFile&) = delete;
  ~MappedFile() { close(); }

  // Maps `path`; on failure returns false and sets *why ("missing", "cannot map ...").
  bool open(const std::string& path, std::string* why) {
    close();
    const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0) {
      *why = errno == ENOENT ? "missing" : std::string("cannot open: ") + std::strerror(errno);
      return false;
    }
    struct stat st {};
    if (::fstat(fd, &st) != 0) {
      *why = std::string("cannot stat: ") + std::strerror(errno);
      ::close(fd);
      return false;
    }
    size_ = size_t(st.st_size);
    if (size_ > 0) {
      void* p = ::mmap(nullptr, size_, PROT_READ, MAP_PRIVATE, fd, 0);
      if (p == MAP_FAILED) {
        *why = std::string("cannot map: ") + std::strerror(errno);
        ::close(fd);
        size_ = 0;
        return false;
      }
      data_ = static_cast<const uint8_t*>(p);
      ::madvise(p, size_, MADV_SEQUENTIAL);
    }
    ::close(fd);
    return true;
  }
  void close() {
    if (data_) ::munmap(const_cast<uint8_t*>(data_), size_);
    data_ = nullptr;
    size_ = 0;
    dropped_ = 0;
  }
  const uint8_t* data() const { return data_; }
  size_t size() const { return size_; }

  // After a pass over the whole file that dropped as it went (a checksum), for the next pass:
  // its drops start again from the file's beginning (else the pages it reads stay mapped).
  void restart_drops() { dropped_ = 0; }

  // Releases the process's pages of [0, offset) once at least `step` bytes are new since the
  // last drop (the file stays mapped; reading there again would fault the pages back in).
  void drop_before(size_t offset, size_t step = size_t(32) << 20) {
    const size_t page = size_t(::sysconf(_SC_PAGESIZE));
    const size_t end = offset / page * page;
    if (!data_ || end <= dropped_ || end - dropped_ < step) return;
    ::madvise(const_cast<uint8_t*>(data_) + dropped_, end - dropped_, MADV_DONTNEED);
    dropped_ = end;
  }

 private:
  const uint8_t* data_ = nullptr;
  size_t size_ = 0, dropped_ = 0;
};

// The header both binary caches start with: magic (8 bytes), format version (u32), key (u64),
// payload size (u64), payload hash (u64); the payload follows.
struct CacheHeader {
  static constexpr size_t kSize = 8 + 4 + 8 + 8 + 8;
  uint32_t version = 0;
  uint64_t key = 0, size = 0, hash = 0;
};

// Checks the header of a mapped cache against what this build expects. nullopt when it fits,
// else why not ("bad magic (not an occswitch <kind>)", "format version ...", `stale_why`, ...).
// On success *out holds the header (its hash is for the caller's payload check).
inline std::optional<std::string> check_cache_header(const MappedFile& f, const char (&magic)[8], const char* kind,
                                                     uint32_t version, uint64_t key, const char* stale_why,
                                                     CacheHeader* out) {
  constexpr size_t kHead = CacheHeader::kSize;
  if (f.size() < kHead) return "truncated header (" + std::to_string(f.size()) + " bytes)";
  if (std::memcmp(f.data(), magic, 8) != 0) return std::string("bad magic (not an occswitch ") + kind + ")";
  CacheHeader h;
  std::memcpy(&h.version, f.data() + 8, 4);
  std::memcpy(&h.key, f.data() + 12, 8);
  std::memcpy(&h.size, f.data() + 20, 8);
  std::memcpy(&h.hash, f.data() + 28, 8);
  if (h.version != version)
    return "format version " + std::to_string(h.version) + ", expected " + std::to_string(version);
  if (h.key != key) return std::string(stale_why);
  if (h.size != f.size() - kHead)
    return "truncated or padded payload (" + std::to_string(f.size() - kHead) + " bytes, header says " +
           std::to_string(h.size) + ")";
  *out = h;
  return std::nullopt;
}

// Moves a fully written temporary cache file to its place (atomic on one file system); on
// failure removes the temporary and says why.
inline std::optional<std::string> commit_cache_file(const std::string& tmp, const std::string& path) {
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (!ec) return std::nullopt;
  std::filesystem::remove(tmp, ec);
  return "cannot rename " + tmp + " to " + path;
}

// A hash of a byte stream that does not depend on how the stream is cut into pieces (unlike
// Hasher::bytes, which hashes each call's length): 8-byte little-endian words, then the tail and
// the total length.
class StreamHash {
 public:
  void feed(const void* data, size_t n) {
    const auto* p = static_cast<const uint8_t*>(data);
    total_ += n;
    while (n > 0 && fill_ > 0) {  // complete a partial word
      carry_[fill_++] = *p++;
      --n;
      if (fill_ == 8) word(carry_), fill_ = 0;
    }
    for (; n >= 8; p += 8, n -= 8) word(p);
    for (; n > 0; --n) carry_[fill_++] = *p++;
  }
  uint64_t value() const {
    Hasher h = h_;
    uint64_t tail = 0;
    std::memcpy(&tail, carry_, fill_);
    h.u64(tail);
    h.u64(total_);
    return h.value();
  }

 private:
  void word(const uint8_t* p) {
    uint64_t w;
    std::memcpy(&w, p, 8);
    h_.u64(w);
  }
  Hasher h_;
  uint8_t carry_[8] = {};
  size_t fill_ = 0;
  uint64_t total_ = 0;
};

}  // namespace occ
