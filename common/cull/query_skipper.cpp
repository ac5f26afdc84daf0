#include "common/cull/query_skipper.hpp"

#include <algorithm>

namespace occ {

bool QuerySkipper::skip(uint32_t node) {
  State& s = state_.at(node);
  if (s.remaining == 0) return false;
  --s.remaining;
  return true;
}

void QuerySkipper::record(uint32_t node, bool visible) {
  State& s = state_.at(node);
  if (!visible) {
    s = State{};
    return;
  }
  if (s.streak < kTrust) ++s.streak;
  if (s.streak < kTrust) return;
  s.wait = uint8_t(std::min<int>(kMaxWait, std::max<int>(2, 2 * s.wait)));
  s.remaining = s.wait;
}

}  // namespace occ
