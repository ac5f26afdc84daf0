// Small deterministic 64-bit hashing used for scene fingerprints, content hashes and the id-set
// hashes (protocol's set_hash, front_hash), and the one hex formatter for printing them.
// Not cryptographic; stable across processes and builds (no std::hash). Header-only: protocol/
// uses it without linking occ_common.
#pragma once
#include <bit>
#include <cstdint>
#include <cstring>
#include <string>
#include <string_view>

namespace occ {

inline uint64_t mix64(uint64_t x) {  // splitmix64 finaliser
  x ^= x >> 30;
  x *= 0xbf58476d1ce4e5b9ULL;
  x ^= x >> 27;
  x *= 0x94d049bb133111ebULL;
  x ^= x >> 31;
  return x;
}

// Order-independent sums over a set of distinct ids: each id's term (a mix64 of the id) added
// and xor-ed in; remove() undoes add(). protocol's set_hash and front_hash (front.hpp) are both
// built on them and differ only in how they finalise (sum, xor, count).
struct IdSetSums {
  uint64_t sum = 0, x = 0;
  static uint64_t term(uint32_t id) { return mix64(id + 0x9e3779b97f4a7c15ULL); }
  void add(uint32_t id) {
    const uint64_t e = term(id);
    sum += e;
    x ^= e;
  }
  void remove(uint32_t id) {
    const uint64_t e = term(id);
    sum -= e;
    x ^= e;
  }
};

// "0x" and the low `digits` hexadecimal digits of v, lowercase and zero-padded: hex(v) gives all
// 16, hex(0x0a, 2) = "0x0a". For error messages and logs.
inline std::string hex(uint64_t v, int digits = 16) {
  std::string s = "0x";
  for (int shift = 4 * (digits - 1); shift >= 0; shift -= 4) s += "0123456789abcdef"[(v >> shift) & 0xf];
  return s;
}

class Hasher {
 public:
  explicit Hasher(uint64_t seed = 0x6f63637377697463ULL) : h_(seed) {}
  void u64(uint64_t v) { h_ = mix64(h_ ^ (v + 0x9e3779b97f4a7c15ULL + (h_ << 6) + (h_ >> 2))); }
  void u32(uint32_t v) { u64(v); }
  void f64(double v) { u64(std::bit_cast<uint64_t>(v == 0.0 ? 0.0 : v)); }
  void f32(float v) { u64(std::bit_cast<uint32_t>(v == 0.0f ? 0.0f : v)); }
  void bytes(const void* data, size_t n) {
    const auto* p = static_cast<const unsigned char*>(data);
    u64(n);
    while (n >= 8) {
      uint64_t w;
      std::memcpy(&w, p, 8);
      u64(w);
      p += 8;
      n -= 8;
    }
    uint64_t tail = 0;
    if (n > 0) std::memcpy(&tail, p, n);  // p may be null when the data is empty
    u64(tail);
  }
  void str(std::string_view s) { bytes(s.data(), s.size()); }
  uint64_t value() const { return mix64(h_); }

 private:
  uint64_t h_;
};

}  // namespace occ
