// The switch node's camera buffer (paper Fig. 2): a receiver thread puts every camera the
// render client sends; the OR stage takes one per frame.
//   lockstep: take(expected) waits for the camera numbered `expected` (reproducible runs).
//   latest:   take_latest(min) returns the newest camera numbered >= min (interactive; older
//             cameras are dropped, as with the paper's buffer of one).
// close() (peer said Bye or disconnected) wakes waiters, who then get the reason. interrupt()
// (the render client sent an instruction, a Resync) makes waiters return nullopt with
// *why = kInterrupted until clear_interrupt(); a pending interrupt wins over a camera.
#pragma once
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <map>
#include <mutex>
#include <optional>
#include <string>

#include "common/camera.hpp"

namespace occ {

struct NumberedCamera {
  uint32_t number = 0;
  Camera camera;
  bool occlusion = true;  // wire.hpp Camera.occlusion: cull this frame with occlusion (OR, queries)
};

class CameraBuffer {
 public:
  static constexpr const char* kInterrupted = "interrupted";
  void put(const NumberedCamera& c);
  void close(const std::string& reason);
  void interrupt();
  void clear_interrupt();

  // nullopt on timeout or close; *why says which.
  std::optional<NumberedCamera> take(uint32_t expected, std::chrono::milliseconds timeout, std::string* why);
  std::optional<NumberedCamera> take_latest(uint32_t min_number, std::chrono::milliseconds timeout,
                                            std::string* why);

 private:
  template <class Pred>
  bool wait(std::unique_lock<std::mutex>& lock, std::chrono::milliseconds timeout, Pred ready, std::string* why);
  std::mutex mu_;
  std::condition_variable cv_;
  std::map<uint32_t, NumberedCamera> cameras_;
  std::optional<std::string> closed_;
  bool interrupted_ = false;
};

}  // namespace occ
