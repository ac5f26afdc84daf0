// One switch node's occlusion back end: the depth its OR draws and the tests HC's traversal runs
// against it, in one object, so occluder fusion and the OR share one "drawn" set and the counts
// come from what did the work. The frame's calls, in order:
//   begin(cam)              the OR: clears the depth for `cam`, nothing drawn;
//   draw(ids) ...           depth only, the ids not in this frame's depth yet (V, the other
//                           node's streamed additions); flush() lets the drawing proceed;
//   begin_tests(frame, cam) HC: from now on the back end answers the traversal as its
//                           OcclusionQueries (issue/result, occluders_found draws through draw(),
//                           leaf_may_show where the back end tests leaves);
//   end_tests()             HC is done; the next frame starts with begin().
// One implementation a file: CpuBackend (cpu_backend.hpp), and on the renderer's depth the
// query, GPU pyramid and CPU pyramid back ends (common/gl/). choose_backend()
// (backend_choice.hpp) picks one at start.
#pragma once
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "common/camera.hpp"
#include "common/cull/culling.hpp"

namespace occ {

// What a back end did, summed over its frames.
struct OcclusionCounts {
  uint64_t boxes_tested = 0;    // boxes the traversal had tested (issue() and issue_cheap())
  uint64_t boxes_occluded = 0;  // of them, answered 0 samples
  // The back end's own counts, each in words ("812 leaves tested by their triangles (300 hidden)").
  std::vector<std::string> more;
};

class OcclusionBackend : public OcclusionQueries {
 public:
  // `renderables`: the id limit of what draw() is given.
  explicit OcclusionBackend(size_t renderables) : drawn_(renderables, 0) {}
  OcclusionBackend(const OcclusionBackend&) = delete;
  OcclusionBackend& operator=(const OcclusionBackend&) = delete;

  virtual const char* name() const = 0;  // backend_name() of its kind
  // A resync: forget what was learnt across frames.
  virtual void restart() {}

  void begin(const Camera& cam);
  // Draws, depth only, those of `ids` not in this frame's depth yet; all count as drawn from now
  // on. Returns how many were drawn now.
  size_t draw(std::span<const uint32_t> ids);
  virtual void flush() {}
  void begin_tests(uint32_t frame, const Camera& cam) {
    testing_ = true;
    start_tests(frame, cam);
  }
  void end_tests() {
    finish_tests();
    testing_ = false;
  }
  // Occluder fusion: draw(found); the tests see what was drawn from the next batch on.
  void occluders_found(std::span<const uint32_t> found) final;

  virtual OcclusionCounts counts() const = 0;

 protected:
  virtual void clear_depth(const Camera& cam) = 0;
  virtual void draw_depth(std::span<const uint32_t> fresh) = 0;
  virtual void start_tests(uint32_t frame, const Camera& cam) = 0;
  virtual void finish_tests() {}
  // Within the tests (between begin_tests() and end_tests()): `fresh` was just drawn.
  virtual void depth_added(std::span<const uint32_t> fresh) = 0;

 private:
  std::vector<uint8_t> drawn_;  // per renderable: in this frame's depth
  std::vector<uint32_t> fresh_;
  bool testing_ = false;
};

}  // namespace occ
