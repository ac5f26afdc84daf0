#include "render_client/viewer.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>

#include "common/camera_path.hpp"
#include "common/error.hpp"
#include "common/progress.hpp"
#include "render_client/web_display.hpp"

namespace occ {

namespace {

// "city:6x6:3:10:1" stays; "/a/b/Duplex.gltf" -> "Duplex".
std::string scene_title(const std::string& spec) {
  if (spec.find('/') == std::string::npos && spec.find(".gl") == std::string::npos) return spec;
  return std::filesystem::path(spec).stem().string();
}

std::optional<NavKey> nav_key(WinKey k) {
  switch (k) {
    case WinKey::w: return NavKey::forward;
    case WinKey::s: return NavKey::back;
    case WinKey::a: return NavKey::left;
    case WinKey::d: return NavKey::right;
    case WinKey::q: return NavKey::down;
    case WinKey::e: return NavKey::up;
    case WinKey::left: return NavKey::look_left;
    case WinKey::right: return NavKey::look_right;
    case WinKey::up: return NavKey::look_up;
    case WinKey::down: return NavKey::look_down;
    case WinKey::shift: return NavKey::fast;
    default: return std::nullopt;
  }
}

std::string screenshot_name(uint32_t index) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "screenshot_%04u.png", index);
  return buf;
}

// The X11 window as a display.
class WindowDisplay : public FrameDisplay {
 public:
  explicit WindowDisplay(std::unique_ptr<X11Window> w) : w_(std::move(w)) {}
  void show(const Image& img, const ShownFrame& f) override { w_->show(img, f.hud); }
  std::vector<WindowEvent> poll(int timeout_ms, int wake_fd) override { return w_->poll(timeout_ms, wake_fd); }

 private:
  std::unique_ptr<X11Window> w_;
};

}  // namespace

Viewer::Viewer(const ClientOptions& o) : o_(o) {
  if (!o.record.empty()) {
    std::ofstream probe(o.record);
    if (!probe) throw InputError("--out: cannot write " + o.record);
  }
  if (!o.web.empty())
    display_ = make_web_display(o);
  else
    display_ = std::make_unique<WindowDisplay>(
        X11Window::open("occswitch \xE2\x80\x94 " + scene_title(o.scene.spec), o.width, o.height));
  if (::pipe2(wake_, O_NONBLOCK | O_CLOEXEC) != 0) throw std::runtime_error("--window: pipe failed");
}

Viewer::~Viewer() {
  try {
    finish();
  } catch (const std::exception& e) {
    std::cerr << "error: render_client: " << e.what() << "\n";
  }
  for (int fd : wake_)
    if (fd >= 0) ::close(fd);
}

void Viewer::start(const Aabb& bounds, const Viewport& vp) {
  interactive_ = o_.path == "interactive";
  if (!interactive_) path_ = load_camera_path(o_.path, bounds, vp);
  const Camera home = interactive_ ? load_camera_path("walk:1", bounds, vp)[0] : path_[0];
  nav_ = std::make_unique<Navigator>(home, bounds);
  std::cerr << "render_client: " << (o_.web.empty() ? "window open" : "web viewer ready") << " ("
            << (interactive_ ? "you drive" : "playing the path; any movement key takes over")
            << "): W/A/S/D/Q/E move, arrows or drag look, Shift faster, wheel speed, F walk/fly, R reset, "
               "P screenshot, O culling overlay, "
            << (o_.web.empty() ? "Esc quits\n" : "the page's stop button quits\n");
  thread_ = std::thread([this] { run_window(); });
}

bool Viewer::next_camera(std::vector<Camera>& cameras) {
  std::unique_lock<std::mutex> lock(mu_);
  if (quit_) return false;
  const size_t n = cameras.size();
  camera_seq_.resize(n + 1);
  camera_seq_[n] = input_seq_;
  if (!interactive_ && !taken_over_) {
    if (n >= path_.size()) return false;
    cameras.push_back(path_[n]);
    nav_->jump_to(path_[n]);  // a take-over starts here
    sent_changes_ = nav_->changes();
    return true;
  }
  // Reference renderer: nothing moves, so wait up to 100 ms for the user first (an idle window
  // refreshes at about 10 fps). Not in the cluster: there pacing the cameras lets frames queue up
  // (in latest mode both nodes may use one camera: two frames per camera sent) and the view lags.
  if (o_.connect.empty() && nav_->changes() == sent_changes_)
    changed_.wait_for(lock, std::chrono::milliseconds(100), [&] { return quit_ || nav_->changes() != sent_changes_; });
  if (quit_) return false;
  sent_changes_ = nav_->changes();
  camera_seq_[n] = input_seq_;  // what the camera includes: events handled until now
  cameras.push_back(nav_->camera());
  return true;
}

void Viewer::show(const Camera& cam, Image img, const HudStats& hud) {
  {
    std::lock_guard<std::mutex> lock(mu_);
    pending_index_ = uint32_t(recorded_.size());
    recorded_.push_back(cam);
    const double t = now_ms();
    const double frame_ms = show_times_ms_.empty() ? 0.0 : t - show_times_ms_.back();
    show_times_ms_.push_back(t);
    while (show_times_ms_.size() > 2 && show_times_ms_.front() < t - 1000) show_times_ms_.erase(show_times_ms_.begin());
    pending_ = std::make_shared<const Image>(std::move(img));
    pending_frame_ = {hud_line(hud), hud, fps(), frame_ms, cam, pending_index_,
                      hud.camera < camera_seq_.size() ? camera_seq_[hud.camera] : 0, dragging_ || nav_->moving()};
  }
  const char c = 1;
  [[maybe_unused]] ssize_t w = ::write(wake_[1], &c, 1);
}

bool Viewer::quit() const {
  std::lock_guard<std::mutex> lock(mu_);
  return quit_;
}

bool Viewer::overlay() const {
  std::lock_guard<std::mutex> lock(mu_);
  return overlay_;
}

double Viewer::fps() const {
  return show_times_ms_.size() > 1
             ? 1000.0 * double(show_times_ms_.size() - 1) / (show_times_ms_.back() - show_times_ms_.front())
             : 0.0;
}

std::string Viewer::hud_line(const HudStats& h) const {
  const double fps = this->fps();
  const double culled = h.leaves ? 100.0 * (1.0 - double(h.visible) / double(h.leaves)) : 0.0;
  char buf[256];
  std::snprintf(buf, sizeof buf, "%.1f fps  %.0f ms  |V| %zu  culled %.1f%%  %.2fM tri  tau %g  %s%s", fps,
                h.latency_ms, h.visible, culled, double(h.triangles) / 1e6, h.tau, nav_->walking() ? "walk" : "fly",
                interactive_ || taken_over_ ? "" : "  (path)");
  std::string s = buf;
  if (h.occluded >= 0) s += "  overlay: " + std::to_string(h.occluded) + " occluded";
  if (!h.mode.empty() && h.mode != "switch") s = "[" + h.mode + "]  " + s;
  if (!message_.empty() && now_ms() < message_until_ms_) s = message_ + "  " + s;
  return s;
}

void Viewer::handle(const WindowEvent& ev) {
  using T = WindowEvent::Type;
  if (ev.seq) input_seq_ = ev.seq;
  auto take_over = [&] {
    if (!interactive_ && !taken_over_) {
      taken_over_ = true;
      std::cerr << "render_client: you took over the camera at frame " << recorded_.size()
                << " (Esc quits)\n";
    }
  };
  auto say = [&](const std::string& m) {
    message_ = m;
    message_until_ms_ = now_ms() + 2000;
  };
  switch (ev.type) {
    case T::close:
      quit_ = true;
      break;
    case T::focus_out:
      nav_->release_all();
      dragging_ = false;
      break;
    case T::key_down:
      if (auto k = nav_key(ev.key)) {
        if (*k != NavKey::fast) take_over();
        nav_->press(*k);
      } else if (ev.key == WinKey::escape) {
        quit_ = true;
      } else if (ev.key == WinKey::f) {
        nav_->toggle_walk();
        say(nav_->walking() ? "walk" : "fly");
      } else if (ev.key == WinKey::r) {
        take_over();
        nav_->reset();
        say("reset");
      } else if (ev.key == WinKey::p) {
        screenshot_ = true;
      } else if (ev.key == WinKey::o) {
        overlay_ = !overlay_;
        std::cerr << "render_client: culling overlay " << (overlay_ ? "on" : "off") << "\n";
        say(!overlay_ ? "culling overlay off"
                      : o_.connect.empty() ? "culling overlay: the reference renderer culls no occluded boxes"
                                     : "culling overlay: occlusion-culled boxes in orange");
      }
      break;
    case T::key_up:
      if (auto k = nav_key(ev.key)) nav_->release(*k);
      break;
    case T::button_down:
      if (ev.button == 1) {
        dragging_ = true;
        drag_x_ = ev.x;
        drag_y_ = ev.y;
      } else if (ev.button == 4 || ev.button == 5) {
        nav_->wheel(ev.button == 4 ? 1 : -1);
        char buf[64];
        std::snprintf(buf, sizeof buf, "speed %.3g/s", nav_->speed());
        say(buf);
      }
      break;
    case T::button_up:
      if (ev.button == 1) dragging_ = false;
      break;
    case T::motion:
      if (dragging_ && (ev.x != drag_x_ || ev.y != drag_y_)) {
        take_over();
        nav_->drag(ev.x - drag_x_, ev.y - drag_y_);
        drag_x_ = ev.x;
        drag_y_ = ev.y;
      }
      break;
  }
}

void Viewer::run_window() {
  double last = now_ms();
  for (;;) {
    bool moving;
    {
      std::lock_guard<std::mutex> lock(mu_);
      if (stop_) return;
      moving = nav_->moving();
    }
    std::vector<WindowEvent> events = display_->poll(moving ? 15 : 200, wake_[0]);
    std::shared_ptr<const Image> to_show, shot;
    ShownFrame frame;
    uint32_t shot_index = 0;
    {
      std::lock_guard<std::mutex> lock(mu_);
      const uint64_t before = nav_->changes();
      const bool was_quit = quit_;
      for (const WindowEvent& ev : events) handle(ev);
      const double t = now_ms();
      nav_->advance(std::min(t - last, 250.0) / 1000.0);
      last = t;
      if (pending_) {
        to_show = std::move(pending_);
        frame = pending_frame_;
        displayed_ = to_show;
        displayed_index_ = pending_index_;
      }
      if (screenshot_) {
        screenshot_ = false;
        shot = displayed_;
        shot_index = displayed_index_;
      }
      if (nav_->changes() != before || quit_ != was_quit) changed_.notify_all();
    }
    if (to_show) display_->show(*to_show, frame);
    if (shot) {
      const std::string dir = o_.out.empty() ? "." : o_.out;
      const std::string file = dir + "/" + screenshot_name(shot_index);
      try {
        std::filesystem::create_directories(dir);
        write_png(file, *shot);
        std::cerr << "render_client: screenshot " << file << " (frame " << shot_index << " of the recording)\n";
      } catch (const std::exception& e) {
        std::cerr << "render_client: screenshot failed: " << e.what() << "\n";
      }
    }
  }
}

void Viewer::finish() {
  {
    std::lock_guard<std::mutex> lock(mu_);
    if (finished_) return;
    finished_ = true;
    stop_ = true;
    changed_.notify_all();
  }
  if (wake_[1] >= 0) {
    const char c = 0;
    [[maybe_unused]] ssize_t w = ::write(wake_[1], &c, 1);
  }
  if (thread_.joinable()) thread_.join();
  if (!o_.record.empty()) {
    if (recorded_.empty()) {
      std::cerr << "render_client: no frame shown, " << o_.record << " left empty\n";
    } else {
      save_camera_path(o_.record, recorded_);
      std::cerr << "render_client: recorded " << recorded_.size() << " cameras to " << o_.record
                << " (replay: --path " << o_.record << ")\n";
    }
  }
}

}  // namespace occ
