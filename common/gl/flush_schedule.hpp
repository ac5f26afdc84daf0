// When SceneRenderer calls glFlush in the middle of a frame. llvmpipe bins a whole frame on the
// calling thread and rasterises it only at a flush, so without one the two run one after the
// other; a flush hands each part to the rasteriser thread while the next is binned. Frames are
// unchanged by any part size (test SceneRenderer.FlushingEveryFewTrianglesDrawsTheSameFrames).
//
// Two policies:
//   fixed      parts of N triangles (0: no flushes); the default, N = kMaxPart;
//   automatic  parts of an eighth of each draw call's triangles, at least kMinPart and at most
//              kMaxPart (part_of), so that small frames are split too. For a process with the
//              cores to itself (the reference renderer and the baselines); not in the cluster,
//              where every part is one more llvmpipe scene on cores three processes share
//              (docs/results.md "Flush parts").
// Besides the policy, the schedule counts what was submitted since the last flush: a draw path
// calls begin_call() for each draw call, cuts its indirect draws where fits() says no, and
// flushes where submitted() says so.
#pragma once
#include <algorithm>
#include <cstdint>
#include <optional>

namespace occ {

class FlushSchedule {
 public:
  // Automatic parts: kParts to a draw call, each of kMinPart to kMaxPart triangles.
  static constexpr uint32_t kParts = 8, kMinPart = 2000, kMaxPart = 20000;
  // The automatic part of a draw call of `call_triangles`.
  static uint32_t part_of(uint64_t call_triangles) {
    return uint32_t(std::clamp<uint64_t>(call_triangles / kParts, kMinPart, kMaxPart));
  }

  // Fixed parts of `part_triangles` (nullopt: automatic). What is counted since the last flush
  // stays.
  void request(std::optional<uint32_t> part_triangles) { fixed_ = part_triangles; }
  // The fixed part size (nullopt: automatic).
  std::optional<uint32_t> fixed() const { return fixed_; }

  // A draw call of `call_triangles` starts: its part size (the fixed one, or part_of).
  void begin_call(uint64_t call_triangles) { part_ = fixed_ ? *fixed_ : part_of(call_triangles); }
  // Query draws: the fixed part size, kMaxPart when automatic.
  void begin_queries() { part_ = fixed_.value_or(kMaxPart); }
  // Whether `triangles` more still fit the current part before a flush is due.
  bool fits(uint64_t triangles) const { return part_ == 0 || unflushed_ + triangles < part_; }
  // `triangles` were submitted: true when a glFlush is due now (the count starts again).
  bool submitted(uint64_t triangles) {
    unflushed_ += triangles;
    if (part_ == 0 || unflushed_ < part_) return false;
    unflushed_ = 0;
    return true;
  }

 private:
  std::optional<uint32_t> fixed_ = kMaxPart;  // none: automatic
  uint32_t part_ = kMaxPart;                  // this draw call's part size (0: no flushes)
  uint64_t unflushed_ = 0;                    // submitted since the last glFlush
};

}  // namespace occ
