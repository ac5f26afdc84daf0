#include "render_client/web_display.hpp"

#include <fcntl.h>
#include <poll.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <map>
#include <mutex>
#include <stdexcept>

#include "common/camera_path.hpp"
#include "render_client/frame_encoder.hpp"
#include "render_client/web_server.hpp"

namespace occ {

namespace {

constexpr int kJpegQuality = 80;

std::string json_string(const std::string& s) {
  std::string out = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') out += '\\';
    if (static_cast<unsigned char>(c) >= 0x20) out += c;
  }
  return out + "\"";
}

void drain(int fd) {
  char buf[64];
  while (::read(fd, buf, sizeof buf) > 0) {
  }
}

class WebDisplay : public FrameDisplay {
 public:
  explicit WebDisplay(const ClientOptions& o) : jpeg_(make_jpeg_encoder(kJpegQuality)), png_(make_png_encoder()) {
    if (::pipe2(wake_, O_NONBLOCK | O_CLOEXEC) != 0) throw std::runtime_error("--web: pipe failed");
    server_ = std::make_unique<WebServer>(parse_web_options(o.web, o.web_tls), [this](const WebInput& in) { push(in); });
  }
  ~WebDisplay() override {
    server_.reset();  // no more input calls
    for (int fd : wake_) ::close(fd);
  }

  void show(const Image& img, const ShownFrame& f) override {
    const std::string camera = camera_csv_fields(f.camera);
    const bool still = camera == last_camera_;
    // Nothing new: the lossless frame of this camera went out already, or the user is between
    // two moves of a drag (or of a held key).
    if (still && (last_was_png_ || f.steering)) return;
    FrameEncoder& enc = still ? *png_ : *jpeg_;
    const auto t0 = std::chrono::steady_clock::now();
    std::vector<uint8_t> bytes;
    try {
      bytes = enc.encode(img);
    } catch (const std::exception& e) {  // the frame is dropped, the next one tried
      std::cerr << "render_client: web: frame " << f.index << " not sent: " << e.what() << "\n";
      return;
    }
    const auto t1 = std::chrono::steady_clock::now();
    const double ms = std::chrono::duration<double, std::milli>(t1 - t0).count();
    const std::string header = web_frame_header(f, enc.format(), img.width, img.height, ms, input_ms(f.input_seq, t1));
    auto message = std::make_shared<std::string>();
    const uint32_t n = uint32_t(header.size());
    for (int i = 0; i < 4; ++i) message->push_back(char((n >> (8 * i)) & 0xff));
    *message += header;
    message->append(reinterpret_cast<const char*>(bytes.data()), bytes.size());
    server_->publish(std::move(message));
    last_camera_ = camera;
    last_was_png_ = still;
  }

  std::vector<WindowEvent> poll(int timeout_ms, int wake_fd) override {
    pollfd fds[2] = {{wake_[0], POLLIN, 0}, {wake_fd, POLLIN, 0}};
    ::poll(fds, wake_fd >= 0 ? 2 : 1, timeout_ms);
    drain(wake_[0]);
    if (wake_fd >= 0 && (fds[1].revents & POLLIN)) drain(wake_fd);
    std::lock_guard<std::mutex> lock(mu_);
    return std::move(events_);
  }

 private:
  // The time from the arrival of input `seq` to `now` (its first frame, encoded); -1 when the
  // frame brings no new input. Arrivals up to `seq` are forgotten.
  double input_ms(uint32_t seq, std::chrono::steady_clock::time_point now) {
    std::lock_guard<std::mutex> lock(mu_);
    const auto it = arrived_.find(seq);
    const double ms = it == arrived_.end() ? -1.0 : std::chrono::duration<double, std::milli>(now - it->second).count();
    arrived_.erase(arrived_.begin(), arrived_.upper_bound(seq));
    return ms;
  }

  // Server thread: one input, as window events (a wheel of N notches: N button events).
  void push(const WebInput& in) {
    {
      std::lock_guard<std::mutex> lock(mu_);
      if (in.seq > 0 && arrived_.size() < kMaxArrivals) arrived_.emplace(in.seq, std::chrono::steady_clock::now());
      const WindowEvent ev = to_window_event(in);
      const int repeat = in.kind == WebInput::Kind::wheel ? std::abs(in.notches) : 1;
      for (int i = 0; i < repeat; ++i) events_.push_back(ev);
    }
    const char c = 1;
    [[maybe_unused]] ssize_t w = ::write(wake_[1], &c, 1);
  }

  std::unique_ptr<FrameEncoder> jpeg_, png_;
  int wake_[2] = {-1, -1};
  std::mutex mu_;
  std::vector<WindowEvent> events_;  // from the server thread, taken by poll()
  static constexpr size_t kMaxArrivals = 4096;  // inputs not yet in a frame sent (the oldest kept)
  std::map<uint32_t, std::chrono::steady_clock::time_point> arrived_;  // input seq -> its arrival
  std::string last_camera_;
  bool last_was_png_ = false;
  std::unique_ptr<WebServer> server_;  // last: stopped first
};

WinKey win_key(WebKey k) {
  switch (k) {
    case WebKey::w: return WinKey::w;
    case WebKey::a: return WinKey::a;
    case WebKey::s: return WinKey::s;
    case WebKey::d: return WinKey::d;
    case WebKey::q: return WinKey::q;
    case WebKey::e: return WinKey::e;
    case WebKey::f: return WinKey::f;
    case WebKey::r: return WinKey::r;
    case WebKey::p: return WinKey::p;
    case WebKey::o: return WinKey::o;
    case WebKey::up: return WinKey::up;
    case WebKey::down: return WinKey::down;
    case WebKey::left: return WinKey::left;
    case WebKey::right: return WinKey::right;
    case WebKey::shift: return WinKey::shift;
    case WebKey::none: break;
  }
  return WinKey::other;
}

}  // namespace

WindowEvent to_window_event(const WebInput& in) {
  using T = WindowEvent::Type;
  using K = WebInput::Kind;
  WindowEvent ev{T::focus_out};
  switch (in.kind) {
    case K::key_down: ev = {T::key_down, win_key(in.key)}; break;
    case K::key_up: ev = {T::key_up, win_key(in.key)}; break;
    case K::button_down: ev = {T::button_down, WinKey::other, in.button, in.x, in.y}; break;
    case K::button_up: ev = {T::button_up, WinKey::other, in.button, in.x, in.y}; break;
    case K::motion: ev = {T::motion, WinKey::other, 0, in.x, in.y}; break;
    case K::wheel: ev = {T::button_down, WinKey::other, in.notches > 0 ? 4 : 5}; break;
    case K::blur: break;
    case K::quit: ev = {T::close}; break;
    case K::ping: break;  // the session answers it; never handed to the viewer
  }
  ev.seq = in.seq;
  return ev;
}

std::string web_frame_header(const ShownFrame& f, const char* format, int width, int height, double encode_ms,
                             double input_ms) {
  const HudStats& h = f.stats;
  const double culled = h.leaves ? 100.0 * (1.0 - double(h.visible) / double(h.leaves)) : 0.0;
  char nums[512];
  std::snprintf(nums, sizeof nums,
                "\"frame\":%u,\"seq\":%u,\"width\":%d,\"height\":%d,\"fps\":%.2f,\"frame_ms\":%.2f,\"latency_ms\":%.2f,"
                "\"visible\":%zu,\"leaves\":%zu,\"culled_pct\":%.2f,\"triangles\":%llu,\"tau\":%g,\"encode_ms\":%.3f,\"input_ms\":%.2f",
                f.index, f.input_seq, width, height, f.fps, f.frame_ms, h.latency_ms, h.visible, h.leaves, culled,
                static_cast<unsigned long long>(h.triangles), h.tau, encode_ms, input_ms);
  return std::string("{\"format\":") + json_string(format) + "," + nums + ",\"mode\":" + json_string(h.mode) +
         ",\"camera\":" + json_string(camera_csv_fields(f.camera)) + ",\"hud\":" + json_string(f.hud) + "}";
}

std::unique_ptr<FrameDisplay> make_web_display(const ClientOptions& o) { return std::make_unique<WebDisplay>(o); }

}  // namespace occ
