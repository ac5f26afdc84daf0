// The camera-receiver thread of a culling server (a switch node or the occlusion_server; paper
// Fig. 2): every camera the render client sends goes into a CameraBuffer, where the OR stage
// takes one per frame. A Resync (the render client's instruction to start over, wire.hpp) is
// queued in order and interrupts the buffer's waiters. The client's Bye, its failure, or anything
// else (including a camera for another viewport) closes the buffer with the reason.
#pragma once
#include <atomic>
#include <deque>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

#include "common/camera.hpp"
#include "common/camera_buffer.hpp"
#include "protocol/net/transport.hpp"

namespace occ {

class CameraReceiver {
 public:
  // Starts the thread; `client` and `cameras` must outlive this object.
  CameraReceiver(net::Connection& client, CameraBuffer& cameras, Viewport viewport);
  ~CameraReceiver();  // joins (the thread ends when the client's connection ends)
  CameraReceiver(const CameraReceiver&) = delete;
  CameraReceiver& operator=(const CameraReceiver&) = delete;

  void join();
  // The client's connection ended: with its Bye (client_said_bye()) or otherwise.
  bool done() const { return done_; }
  bool client_said_bye() const { return bye_; }
  std::string end_reason() const;  // "render client closed: peer said bye: done", ...
  // The oldest Resync not yet taken (the buffer stays interrupted while more are queued).
  std::optional<wire::Resync> take_resync();
  bool resync_pending() const;

 private:
  void run();
  net::Connection& client_;
  CameraBuffer& cameras_;
  Viewport viewport_;
  mutable std::mutex mu_;
  std::string end_;
  std::deque<wire::Resync> resyncs_;
  std::atomic<bool> bye_{false}, done_{false};
  std::thread thread_;
};

}  // namespace occ
