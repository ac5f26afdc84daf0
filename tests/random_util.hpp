// The tests' small deterministic random source: a 64-bit linear congruential generator (Knuth's
// MMIX constants) whose call gives a double uniform in [0, 1) from its top 53 bits. The same
// seed gives the same sequence everywhere, unlike the standard distributions.
#pragma once
#include <cstdint>

namespace occtest {

struct Lcg {
  uint64_t state;
  double operator()() {
    state = state * 6364136223846793005ULL + 1442695040888963407ULL;
    return double(state >> 11) / double(1ULL << 53);
  }
};

}  // namespace occtest
