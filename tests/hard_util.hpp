// Helpers for the hard-case tests (tests/hard_*.cpp): pinned camera paths written as CSV, the
// three real processes (switch_node 0, switch_node 1, render_client) on 127.0.0.1 with port files,
// the reference renderer with no culling at all (--cull none: the ground truth, so a wrong
// frustum test cannot hide in both renderers), frame_diff, and background-pixel counts.
#pragma once
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "common/camera.hpp"
#include "common/camera_path.hpp"
#include "common/image.hpp"
#include "integration_util.hpp"

namespace occtest {

using namespace std::chrono_literals;

struct View {
  int width = 128;
  int height = 96;
  double aspect() const { return double(width) / height; }
  std::vector<std::string> args() const {
    return {"--width", std::to_string(width), "--height", std::to_string(height)};
  }
};

// A camera for a pinned path; aspect comes from the viewport when the CSV is loaded.
inline occ::Camera cam(glm::dvec3 eye, glm::dvec3 target, double fovy_deg = 60, double near_dist = 0.05,
                       double far_dist = 500, glm::dvec3 up = {0, 1, 0}) {
  return occ::Camera::look_at(eye, target, up, fovy_deg, 1.0, near_dist, far_dist);
}

inline std::vector<occ::Camera> translated(std::vector<occ::Camera> path, const glm::dvec3& d) {
  for (auto& c : path) c.eye += d;
  return path;
}

inline std::string write_path(const fs::path& file, const std::vector<occ::Camera>& path) {
  occ::save_camera_path(file.string(), path);
  return file.string();
}

struct ClusterRun {
  int rvg_code = -1, node0_code = -1, node1_code = -1;
  std::string rvg_log, node0_log, node1_log;
  std::string logs() const {
    return "--- render_client\n" + rvg_log + "--- node 0\n" + node0_log + "--- node 1\n" + node1_log;
  }
};

// Node 0, node 1 and the render client like scripts/cluster.sh (lockstep cameras).
inline ClusterRun run_cluster(const fs::path& out, const std::string& scene, const std::string& path,
                              const View& view, std::vector<std::string> rvg_extra = {}) {
  fs::create_directories(out);
  std::vector<std::string> common = {"--scene", scene, "--timeout-ms", "30000"};
  for (auto& a : view.args()) common.push_back(a);
  auto args = [&](std::vector<std::string> a, const std::vector<std::string>& more = {}) {
    a.insert(a.end(), common.begin(), common.end());
    a.insert(a.end(), more.begin(), more.end());
    return a;
  };
  Proc n0(args({bin("switch_node"), "--id", "0", "--port-file", (out / "n0.port").string()}), out / "node0.log");
  const int p0 = wait_port(out / "n0.port", n0);
  Proc n1(args({bin("switch_node"), "--id", "1", "--peer", "127.0.0.1:" + std::to_string(p0), "--port-file",
                (out / "n1.port").string()}),
          out / "node1.log");
  const int p1 = wait_port(out / "n1.port", n1);
  ClusterRun r;
  if (p0 && p1) {
    Proc rvg(args({bin("render_client"), "--path", path, "--out", out.string(), "--connect",
                   "127.0.0.1:" + std::to_string(p0), "--connect", "127.0.0.1:" + std::to_string(p1)},
                  rvg_extra),
             out / "render_client.log");
    r.rvg_code = rvg.wait(300s);
    r.rvg_log = rvg.log();
  }
  r.node0_code = n0.wait(60s);
  r.node1_code = n1.wait(60s);
  r.node0_log = n0.log();
  r.node1_log = n1.log();
  return r;
}

// The reference renderer drawing every leaf (no culling): exit code.
inline int run_reference(const fs::path& out, const std::string& scene, const std::string& path, const View& view) {
  fs::create_directories(out);
  std::vector<std::string> a = {bin("render_client"), "--reference", "--cull", "none", "--scene", scene,
                                "--path", path, "--out", out.string()};
  for (auto& v : view.args()) a.push_back(v);
  Proc p(a, out / "reference.log");
  return p.wait(300s);
}

// frame_diff exit code (0: every frame within budget); its output in *log.
inline int frame_diff(const fs::path& a, const fs::path& b, std::string* log, double max_fraction = 0.0001,
                      int threshold = 0) {
  static int n = 0;
  const fs::path log_file = a / ("diff_" + std::to_string(n++) + ".log");
  Proc p({bin("frame_diff"), a.string(), b.string(), "--max-fraction", std::to_string(max_fraction), "--threshold",
          std::to_string(threshold)},
         log_file);
  const int code = p.wait(120s);
  *log = p.log();
  return code;
}

// Pixels of frame f showing the background colour (SceneRenderer::kBackgroundRgba8 = 20,23,28):
// a missing object shows as more background.
inline size_t background_pixels(const fs::path& dir, size_t frame) {
  char name[32];
  std::snprintf(name, sizeof name, "frame_%05zu.png", frame);
  const occ::Image img = occ::read_png((dir / name).string());
  size_t n = 0;
  for (size_t p = 0; p + 3 < img.rgba.size(); p += 4)
    n += img.rgba[p] == 20 && img.rgba[p + 1] == 23 && img.rgba[p + 2] == 28;
  return n;
}

inline size_t frame_count(const fs::path& dir) {
  size_t n = 0;
  for (auto& e : fs::directory_iterator(dir)) {
    const std::string f = e.path().filename().string();
    n += f.rfind("frame_", 0) == 0 && f.size() > 4 && f.substr(f.size() - 4) == ".png";
  }
  return n;
}

// The main check of every hard case: the cluster (three real processes) renders exactly what the
// reference renders, frame by frame (frame_diff --max-fraction 0.0001, as in the cluster tests).
// Returns the directory holding cluster/ and reference/.
inline fs::path expect_cluster_equals_reference(const std::string& name, const std::string& scene,
                                                const std::vector<occ::Camera>& path, const View& view = {}) {
  const fs::path dir = fresh_dir("hard_" + name);
  const std::string csv = write_path(dir / "path.csv", path);
  const ClusterRun r = run_cluster(dir / "cluster", scene, csv, view);
  EXPECT_EQ(r.rvg_code, 0) << r.logs();
  EXPECT_EQ(r.node0_code, 0) << r.logs();
  EXPECT_EQ(r.node1_code, 0) << r.logs();
  EXPECT_EQ(run_reference(dir / "reference", scene, csv, view), 0) << read_file(dir / "reference" / "reference.log");
  if (r.rvg_code != 0) return dir;
  EXPECT_EQ(frame_count(dir / "cluster"), path.size());
  std::string log;
  EXPECT_EQ(frame_diff(dir / "reference", dir / "cluster", &log), 0) << name << ": cluster != reference\n" << log;
  return dir;
}

}  // namespace occtest
