#include "common/camera_buffer.hpp"

namespace occ {

void CameraBuffer::put(const NumberedCamera& c) {
  {
    std::lock_guard lock(mu_);
    cameras_[c.number] = c;
    while (cameras_.size() > 64) cameras_.erase(cameras_.begin());  // bounded: oldest go first
  }
  cv_.notify_all();
}

void CameraBuffer::close(const std::string& reason) {
  {
    std::lock_guard lock(mu_);
    if (!closed_) closed_ = reason;
  }
  cv_.notify_all();
}

void CameraBuffer::interrupt() {
  {
    std::lock_guard lock(mu_);
    interrupted_ = true;
  }
  cv_.notify_all();
}

void CameraBuffer::clear_interrupt() {
  std::lock_guard lock(mu_);
  interrupted_ = false;
}

template <class Pred>
bool CameraBuffer::wait(std::unique_lock<std::mutex>& lock, std::chrono::milliseconds timeout, Pred ready,
                        std::string* why) {
  bool ok = cv_.wait_for(lock, timeout, [&] { return interrupted_ || ready() || closed_.has_value(); });
  if (interrupted_) {
    if (why) *why = kInterrupted;
    return false;
  }
  if (ok && ready()) return true;
  if (why) *why = closed_ ? *closed_ : "timed out after " + std::to_string(timeout.count()) + " ms waiting for a camera";
  return false;
}

std::optional<NumberedCamera> CameraBuffer::take(uint32_t expected, std::chrono::milliseconds timeout,
                                                 std::string* why) {
  std::unique_lock lock(mu_);
  if (!wait(lock, timeout, [&] { return cameras_.count(expected) > 0; }, why)) return std::nullopt;
  NumberedCamera out = cameras_.at(expected);
  cameras_.erase(cameras_.begin(), cameras_.upper_bound(expected));
  return out;
}

std::optional<NumberedCamera> CameraBuffer::take_latest(uint32_t min_number, std::chrono::milliseconds timeout,
                                                        std::string* why) {
  std::unique_lock lock(mu_);
  auto has = [&] { return !cameras_.empty() && cameras_.rbegin()->first >= min_number; };
  if (!wait(lock, timeout, has, why)) return std::nullopt;
  NumberedCamera out = cameras_.rbegin()->second;
  cameras_.clear();
  return out;
}

}  // namespace occ
