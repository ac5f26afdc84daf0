// The camera-receiver thread of a culling server (a switch node or the occlusion_server; paper
// Fig. 2): every camera the render client sends goes into a CameraBuffer, where the OR stage
// takes one per frame. The client's Bye, its failure, or anything but a camera (including a
// camera for another viewport) closes the buffer with the reason.
#pragma once
#include <atomic>
#include <mutex>
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

 private:
  void run();
  net::Connection& client_;
  CameraBuffer& cameras_;
  Viewport viewport_;
  mutable std::mutex mu_;
  std::string end_;
  std::atomic<bool> bye_{false}, done_{false};
  std::thread thread_;
};

}  // namespace occ
