#include "protocol/cluster/camera_receiver.hpp"

#include "protocol/cluster/cluster.hpp"

namespace occ {

CameraReceiver::CameraReceiver(net::Connection& client, CameraBuffer& cameras, Viewport viewport)
    : client_(client), cameras_(cameras), viewport_(viewport), thread_([this] { run(); }) {}

CameraReceiver::~CameraReceiver() { join(); }

void CameraReceiver::join() {
  if (thread_.joinable()) thread_.join();
}

std::string CameraReceiver::end_reason() const {
  std::lock_guard<std::mutex> lock(mu_);
  return end_;
}

std::optional<wire::Resync> CameraReceiver::take_resync() {
  std::lock_guard<std::mutex> lock(mu_);
  if (resyncs_.empty()) return std::nullopt;
  wire::Resync r = resyncs_.front();
  resyncs_.pop_front();
  if (resyncs_.empty()) cameras_.clear_interrupt();
  return r;
}

bool CameraReceiver::resync_pending() const {
  std::lock_guard<std::mutex> lock(mu_);
  return !resyncs_.empty();
}

void CameraReceiver::run() {
  auto finish = [&](const std::string& why, bool bye) {
    {
      std::lock_guard<std::mutex> lock(mu_);
      end_ = why;
    }
    bye_ = bye;
    cameras_.close(why);
    done_ = true;
  };
  for (;;) {
    net::Received r = client_.receive(net::Millis(1000));
    if (r.status == net::Received::Status::timeout) continue;
    if (!r.ok()) {
      const bool bye = r.status == net::Received::Status::closed;
      return finish((bye ? "render client closed: " : "render client failed: ") + r.reason, bye);
    }
    if (const auto* rs = std::get_if<wire::Resync>(&r.message)) {
      std::lock_guard<std::mutex> lock(mu_);  // then the buffer's lock, as in take_resync()
      resyncs_.push_back(*rs);
      cameras_.interrupt();
      continue;
    }
    const auto* c = std::get_if<wire::Camera>(&r.message);
    std::string wrong;
    if (!c)
      wrong = "unexpected " + std::string(wire::type_name(wire::type_of(r.message))) + " from the render client";
    else if (auto err = viewport_mismatch(*c, viewport_))
      wrong = "render client: " + *err;
    if (!wrong.empty()) {
      client_.close_with_error(wrong);
      return finish(wrong, false);
    }
    cameras_.put({c->frame, from_wire(*c), c->occlusion != 0});
  }
}

}  // namespace occ
