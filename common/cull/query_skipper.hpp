// Adaptive queries: which nodes HC's traversal may take as visible without a test
// (HcChoices::adaptive_queries, HcOptions::skipper).
#pragma once
#include <cstdint>
#include <vector>

#include "common/scene/hierarchy.hpp"

namespace occ {

// Pays for occlusion queries only where they cull (the cost/benefit idea of the hardware-assisted
// culling paper): a node whose query came back visible kTrust times in a row is assumed visible,
// without a query, for its next `wait` visits; every confirmation doubles the wait (up to
// kMaxWait), an occluded result resets it. Assuming visible is conservative: the node is accepted
// or descended exactly as if its query had passed, so no frame changes; only the visible set may
// keep a node for up to kMaxWait visits after it became occluded (where the querier has
// cheap_tests(), only while its cheap test cannot prove that). A scene with little occlusion
// (an open field, the outside of one object) thus stops paying for queries that never cull.
class QuerySkipper {
 public:
  static constexpr uint8_t kTrust = 2;
  static constexpr uint8_t kMaxWait = 32;
  // A leaf with more triangles than this is queried every time: skipping its query saves one
  // box test, but if it has become occluded it is drawn for nothing, twice (the other node's
  // OR and the render client), for up to kMaxWait frames.
  static constexpr uint64_t kMaxSkippedLeafTriangles = 150;
  // Whether `n`'s query may be skipped at all (interior nodes: their children are tested).
  static bool may_skip(const HNode& n) { return !n.leaf() || n.triangles <= kMaxSkippedLeafTriangles; }
  explicit QuerySkipper(size_t nodes) : state_(nodes) {}
  // True when `node` is assumed visible this time (consumes one visit of its wait).
  bool skip(uint32_t node);
  void record(uint32_t node, bool visible);

 private:
  struct State {
    uint8_t streak = 0, wait = 0, remaining = 0;
  };
  std::vector<State> state_;
};

}  // namespace occ
