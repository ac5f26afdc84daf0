// Helpers for the hard-case tests (tests/hard_*.cpp): pinned camera paths written as CSV, the
// three real processes (cluster_run.hpp) with the hard cases' options, the reference renderer
// with no culling at all (--cull none: the ground truth, so a wrong frustum test cannot hide in
// both renderers), and background-pixel counts.
#pragma once
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "common/camera.hpp"
#include "common/camera_path.hpp"
#include "common/image.hpp"
#include "cluster_run.hpp"

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

// The cluster of the hard cases (cluster_run.hpp): lockstep cameras from a CSV path; the
// processes' timeouts are 30 s.
inline ClusterOptions hard_cluster(const std::string& scene, const std::string& path, const View& view) {
  ClusterOptions o(scene, path, view.args());
  o.timeout_ms = 30000;
  o.node_wait = 60s;
  return o;
}

// The reference renderer drawing every leaf (no culling): the ground truth of the hard cases.
inline std::vector<std::string> unculled(const View& view) {
  std::vector<std::string> a = {"--cull", "none"};
  for (auto& v : view.args()) a.push_back(v);
  return a;
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

// The main check of every hard case: the cluster (three real processes) renders exactly what the
// unculled reference renders, frame by frame (frame_diff --max-fraction 0.0001, as in the cluster
// tests). Returns the directory holding cluster/ and reference/.
inline fs::path expect_cluster_equals_reference(const std::string& name, const std::string& scene,
                                                const std::vector<occ::Camera>& path, const View& view = {}) {
  const fs::path dir = fresh_dir("hard_" + name);
  const std::string csv = write_path(dir / "path.csv", path);
  expect_cluster_equals_reference(dir, hard_cluster(scene, csv, view), unculled(view), path.size());
  return dir;
}

}  // namespace occtest
