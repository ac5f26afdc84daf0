// render_client --window end to end under Xvfb, driven by xdotool: a windowed cluster (latest
// camera mode) moves the camera, records the path, takes a screenshot and quits with Esc, all
// three processes exiting 0; the recorded path replayed by the reference renderer gives the frame
// the screenshot shows. Skipped (with a message) without Xvfb or xdotool.
#include <gtest/gtest.h>
#include <signal.h>

#include <cstdlib>
#include <optional>
#include <regex>
#include <set>

#include "common/camera_path.hpp"
#include "common/image.hpp"
#include "integration_util.hpp"

#include "render_client/x11_lib.hpp"  // last: Xlib's macros (None, Bool, ...) would break the headers above

using namespace occtest;
using namespace std::chrono_literals;

namespace {

const std::vector<std::string> kView = {"--width", "128", "--height", "96"};
const std::string kScene = "city:4x4:2:6:1";

std::string which(const std::string& prog) {
  for (const char* dir : {"/usr/bin", "/usr/local/bin", "/bin"})
    if (fs::exists(std::string(dir) + "/" + prog)) return std::string(dir) + "/" + prog;
  return "";
}

// An Xvfb on a display number it picks itself (-displayfd: free even when tests run in parallel),
// stopped with SIGTERM (it removes its socket and lock) at the end.
class Xvfb {
 public:
  explicit Xvfb(const fs::path& dir) : log_(dir / "xvfb.log") {
    proc_ = std::make_unique<Proc>(std::vector<std::string>{which("Xvfb"), "-displayfd", "1", "-screen", "0",
                                                            "800x600x24", "-nolisten", "tcp"},
                                   log_);
    for (int i = 0; i < 500 && proc_->running(); ++i) {  // it writes the number once it accepts clients
      std::istringstream log(read_file(log_));
      for (std::string line; std::getline(log, line);)
        if (!line.empty() && line.find_first_not_of("0123456789") == std::string::npos && !log.eof()) {
          display_ = ":" + line;
          return;
        }
      std::this_thread::sleep_for(20ms);
    }
  }
  ~Xvfb() {
    if (proc_) {
      proc_->signal(SIGTERM);
      proc_->wait(5s);
    }
  }
  bool ok() { return proc_ && proc_->running() && !display_.empty(); }
  const std::string& display() const { return display_; }
  std::string log() const { return proc_ ? proc_->log() : ""; }

 private:
  fs::path log_;
  std::string display_;
  std::unique_ptr<Proc> proc_;
};

// Runs xdotool with these arguments; its output.
std::string xdotool(const fs::path& dir, std::vector<std::string> args) {
  args.insert(args.begin(), which("xdotool"));
  Proc p(args, dir / "xdotool.log");
  EXPECT_EQ(p.wait(20s), 0) << "xdotool " << args[1] << ": " << p.log();
  return p.log();
}

bool wait_for(const std::function<bool()>& ok, std::chrono::milliseconds timeout) {
  auto end = std::chrono::steady_clock::now() + timeout;
  while (!ok()) {
    if (std::chrono::steady_clock::now() > end) return false;
    std::this_thread::sleep_for(50ms);
  }
  return true;
}

// Each test under its own Xvfb, whose display the processes it starts use (DISPLAY), with a
// fresh folder dir_; skipped (with a message) without Xvfb or xdotool.
class Window : public ::testing::Test {
 protected:
  void SetUp() override {
    if (which("Xvfb").empty() || which("xdotool").empty())
      GTEST_SKIP() << "needs Xvfb and xdotool (Debian packages xvfb, xdotool): not installed";
    dir_ = fresh_dir(std::string("window_") + ::testing::UnitTest::GetInstance()->current_test_info()->name());
    x_.emplace(dir_);
    ASSERT_TRUE(x_->ok()) << "Xvfb did not start: " << x_->log();
    ::setenv("DISPLAY", x_->display().c_str(), 1);  // inherited by the processes the test starts
  }
  // The render client's window (xdotool search), under the pointer and focused: its id ("" if none).
  std::string focused_window() const {
    std::string id = xdotool(dir_, {"search", "--sync", "--name", "occswitch"});
    id = id.substr(0, id.find('\n'));
    if (!id.empty()) {
      xdotool(dir_, {"mousemove", "--window", id, "64", "48"});
      xdotool(dir_, {"windowfocus", id});
    }
    return id;
  }

  fs::path dir_;
  std::optional<Xvfb> x_;
};

// (The tests stay in this namespace: there the fixture's name hides X11's ::Window.)

TEST_F(Window, DriveRecordScreenshotQuitAndReplay) {
  const fs::path out = dir_ / "win", rec = out / "path.csv";
  std::vector<std::string> common = {"--scene", kScene, "--camera-mode", "latest", "--timeout-ms", "20000"};
  common.insert(common.end(), kView.begin(), kView.end());
  auto args = [&](std::vector<std::string> a) {
    a.insert(a.end(), common.begin(), common.end());
    return a;
  };
  Proc n0(args({bin("switch_node"), "--id", "0", "--port-file", (dir_ / "n0.port").string()}), dir_ / "node0.log");
  const int p0 = wait_port(dir_ / "n0.port", n0);
  ASSERT_GT(p0, 0) << n0.log();
  Proc n1(args({bin("switch_node"), "--id", "1", "--peer", "127.0.0.1:" + std::to_string(p0), "--port-file",
                (dir_ / "n1.port").string()}),
          dir_ / "node1.log");
  const int p1 = wait_port(dir_ / "n1.port", n1);
  ASSERT_GT(p1, 0) << n1.log();
  Proc rvg(args({bin("render_client"), "--window", "--out", out.string(), "--images", "off",
                 "--connect", "127.0.0.1:" + std::to_string(p0), "--connect", "127.0.0.1:" + std::to_string(p1)}),
           dir_ / "render_client.log");
  ASSERT_TRUE(wait_for([&] { return rvg.log().find("connected to switch node") != std::string::npos || !rvg.running(); }, 60s))
      << rvg.log();
  ASSERT_TRUE(rvg.running()) << rvg.log();

  // The window, under the pointer and focused; then W held, a drag to the right, Right, P, Esc.
  const std::string id = focused_window();
  ASSERT_FALSE(id.empty());
  std::this_thread::sleep_for(500ms);
  xdotool(dir_, {"keydown", "w", "sleep", "0.4", "keyup", "w"});
  xdotool(dir_, {"mousedown", "1", "mousemove_relative", "--", "15", "0", "mousemove_relative", "--", "15", "5",
                "mouseup", "1"});
  xdotool(dir_, {"key", "Right"});
  std::this_thread::sleep_for(1000ms);  // frames with the new camera arrive and are shown
  xdotool(dir_, {"key", "p"});
  ASSERT_TRUE(wait_for([&] { return rvg.log().find("screenshot ") != std::string::npos || !rvg.running(); }, 10s))
      << rvg.log();
  // O: the culling overlay, then a second screenshot (with it).
  xdotool(dir_, {"key", "o"});
  std::this_thread::sleep_for(1000ms);
  xdotool(dir_, {"key", "p"});
  ASSERT_TRUE(wait_for(
      [&] {
        const std::string l = rvg.log();
        return l.find("screenshot ", l.find("screenshot ") + 1) != std::string::npos || !rvg.running();
      },
      10s))
      << rvg.log();
  xdotool(dir_, {"key", "Escape"});

  EXPECT_EQ(rvg.wait(30s), 0) << rvg.log();
  EXPECT_EQ(n0.wait(30s), 0) << n0.log();
  EXPECT_EQ(n1.wait(30s), 0) << n1.log();

  // The recording: more than one camera, and it moved (eye and view direction).
  const occ::Aabb bounds{{-1e4, -1e4, -1e4}, {1e4, 1e4, 1e4}};  // near/far are in the file
  const auto cams = occ::load_camera_path(rec.string(), bounds, {128, 96});
  ASSERT_GT(cams.size(), 1u);
  EXPECT_GT(glm::length(cams.back().eye - cams.front().eye), 1e-3);
  EXPECT_LT(glm::dot(cams.back().forward(), cams.front().forward()), 0.9999);

  // The screenshot: OUT/screenshot_NNNN.png, NNNN = its frame in the recording; not blank.
  std::smatch m;
  const std::string log = rvg.log();
  ASSERT_TRUE(std::regex_search(log, m, std::regex("screenshot (\\S+screenshot_(\\d+)\\.png)"))) << log;
  const occ::Image shot = occ::read_png(m[1].str());
  const size_t index = std::stoul(m[2].str());
  ASSERT_LT(index, cams.size());
  EXPECT_GT(index, 0u);
  ASSERT_EQ(shot.width, 128);
  ASSERT_EQ(shot.height, 96);
  std::set<uint32_t> colours;
  for (size_t p = 0; p < shot.rgba.size(); p += 4)
    colours.insert(uint32_t(shot.rgba[p]) << 16 | uint32_t(shot.rgba[p + 1]) << 8 | shot.rgba[p + 2]);
  EXPECT_GT(colours.size(), 8u) << "the screenshot is (nearly) one colour";

  // Replaying the recording gives the frame the screenshot shows.
  Proc ref({bin("render_client"), "--scene", kScene, "--path", rec.string(), "--out",
            (dir_ / "replay").string(), kView[0], kView[1], kView[2], kView[3]},
           dir_ / "replay.log");
  ASSERT_EQ(ref.wait(120s), 0) << ref.log();
  char name[32];
  std::snprintf(name, sizeof name, "frame_%05zu.png", index);
  const occ::Image replay = occ::read_png((dir_ / "replay" / name).string());
  ASSERT_EQ(replay.rgba.size(), shot.rgba.size());
  size_t differing = 0;
  for (size_t p = 0; p < shot.rgba.size(); p += 4)
    for (int c = 0; c < 3; ++c)
      if (std::abs(int(shot.rgba[p + c]) - int(replay.rgba[p + c])) > 1) {
        ++differing;
        break;
      }
  EXPECT_EQ(differing, 0u) << "screenshot frame " << index << " vs the replay's " << name;

  // The overlay screenshot: its frame with occlusion-culled boxes tinted orange (more red, less
  // blue) over it, and nothing else changed; --out's frames never carry it.
  EXPECT_NE(log.find("culling overlay on"), std::string::npos) << log;
  const std::string rest = log.substr(size_t(m.position(0) + m.length(0)));
  std::smatch m2;
  ASSERT_TRUE(std::regex_search(rest, m2, std::regex("screenshot (\\S+screenshot_(\\d+)\\.png)"))) << log;
  const occ::Image tinted = occ::read_png(m2[1].str());
  const size_t index2 = std::stoul(m2[2].str());
  ASSERT_LT(index2, cams.size());
  std::snprintf(name, sizeof name, "frame_%05zu.png", index2);
  const occ::Image plain = occ::read_png((dir_ / "replay" / name).string());
  ASSERT_EQ(plain.rgba.size(), tinted.rgba.size());
  size_t tinted_px = 0, other = 0;
  for (size_t p = 0; p < tinted.rgba.size(); p += 4) {
    const int dr = int(tinted.rgba[p]) - int(plain.rgba[p]), dg = int(tinted.rgba[p + 1]) - int(plain.rgba[p + 1]),
              db = int(tinted.rgba[p + 2]) - int(plain.rgba[p + 2]);
    if (std::abs(dr) <= 1 && std::abs(dg) <= 1 && std::abs(db) <= 1) continue;
    (dr >= -1 && db <= 1 && (dr > 1 || db < -1)) ? ++tinted_px : ++other;
  }
  EXPECT_GT(tinted_px, 0u) << "overlay screenshot frame " << index2 << ": nothing tinted";
  EXPECT_EQ(other, 0u) << "overlay screenshot frame " << index2 << ": pixels changed other than by the tint";
}

// The window manager's close button (WM_DELETE_WINDOW) quits cleanly, and a movement key takes
// over a playing path (reference renderer: same viewer as the cluster).
TEST_F(Window, MovementKeyTakesOverAPathCloseButtonQuits) {
  const fs::path rec = dir_ / "ref" / "path.csv";
  Proc ref({bin("render_client"), "--window", "--scene", kScene, "--path", "walk:20000", "--out",
            (dir_ / "ref").string(), "--images", "off", kView[0], kView[1], kView[2], kView[3]},
           dir_ / "reference.log");
  const std::string id = focused_window();
  ASSERT_FALSE(id.empty());
  // The window opens before the scene loads: let the path play a little first.
  ASSERT_TRUE(wait_for([&] { return ref.log().find("GL_RENDERER") != std::string::npos || !ref.running(); }, 60s))
      << ref.log();
  std::this_thread::sleep_for(500ms);
  xdotool(dir_, {"key", "a"});
  ASSERT_TRUE(wait_for([&] { return ref.log().find("you took over") != std::string::npos || !ref.running(); }, 10s))
      << ref.log();
  std::this_thread::sleep_for(300ms);

  // What a window manager sends when the close button is clicked.
  const occ::X11Lib& xl = occ::x11();
  Display* dpy = xl.XOpenDisplay(x_->display().c_str());
  ASSERT_NE(dpy, nullptr);
  XEvent ev{};
  ev.xclient.type = ClientMessage;
  ev.xclient.window = ::Window(std::stoul(id));
  ev.xclient.message_type = xl.XInternAtom(dpy, "WM_PROTOCOLS", False);
  ev.xclient.format = 32;
  ev.xclient.data.l[0] = long(xl.XInternAtom(dpy, "WM_DELETE_WINDOW", False));
  ev.xclient.data.l[1] = CurrentTime;
  xl.XSendEvent(dpy, ev.xclient.window, False, NoEventMask, &ev);
  xl.XFlush(dpy);
  xl.XCloseDisplay(dpy);

  EXPECT_EQ(ref.wait(30s), 0) << ref.log();
  std::smatch m;
  const std::string log = ref.log();
  ASSERT_TRUE(std::regex_search(log, m, std::regex("took over the camera at frame (\\d+)"))) << log;
  const size_t k = std::stoul(m[1].str());
  const occ::Aabb bounds{{-1e4, -1e4, -1e4}, {1e4, 1e4, 1e4}};  // near/far are in the file
  const auto cams = occ::load_camera_path(rec.string(), bounds, {128, 96});
  ASSERT_GT(k, 0u);
  ASSERT_GT(cams.size(), k);
  EXPECT_LT(cams.size(), 20000u) << "the close button did not end the run";
  // A: a step to the left of the last path camera.
  EXPECT_LT(glm::dot(cams.back().eye - cams[k - 1].eye, cams[k - 1].right()), 0.0);
  EXPECT_GT(glm::length(cams.back().eye - cams[k - 1].eye), 1e-3);
}

}  // namespace
