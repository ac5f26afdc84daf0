#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <vector>

#include "common/camera_path.hpp"
#include "common/error.hpp"

using namespace occ;

namespace {
const Aabb kBounds{{-50, 0, -20}, {50, 30, 20}};
const Viewport kVp{320, 240};

// The files write_tmp makes, removed when the test program ends (they used to stay in /tmp).
struct TmpFiles {
  std::vector<std::filesystem::path> paths;
  ~TmpFiles() {
    for (const auto& p : paths) std::filesystem::remove(p);
  }
} g_tmp_files;

std::string write_tmp(const std::string& name, const std::string& text) {
  auto p = std::filesystem::temp_directory_path() / ("occ_path_" + std::to_string(::getpid()) + "_" + name);
  std::ofstream(p) << text;
  g_tmp_files.paths.push_back(p);
  return p.string();
}

std::string error_of(const std::string& spec) {
  try {
    load_camera_path(spec, kBounds, kVp);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}
}  // namespace

TEST(CameraPath, GeneratedPathsHaveRequestedLengthAndValidCameras) {
  for (const char* spec : {"orbit:7", "walk:20", "fly:5"}) {
    auto path = load_camera_path(spec, kBounds, kVp);
    ASSERT_EQ(path.size(), std::stoul(std::string(spec).substr(std::string(spec).find(':') + 1)));
    for (const Camera& c : path) {
      EXPECT_FALSE(c.invalid_reason()) << spec;
      EXPECT_NEAR(c.aspect, 320.0 / 240.0, 1e-12);
    }
  }
}

TEST(CameraPath, WalkStaysAtEyeHeightInsideTheScene) {
  for (const Camera& c : load_camera_path("walk:30", kBounds, kVp)) {
    EXPECT_NEAR(c.eye.y, 1.7, 1e-9);
    EXPECT_TRUE(kBounds.contains(c.eye));
  }
}

TEST(CameraPath, CsvRoundTripsThroughSave) {
  auto path = load_camera_path("orbit:5", kBounds, kVp);
  std::string f = write_tmp("rt.csv", "");
  save_camera_path(f, path);
  auto again = load_camera_path(f, kBounds, kVp);
  ASSERT_EQ(again.size(), path.size());
  for (size_t i = 0; i < path.size(); ++i) {
    EXPECT_NEAR(glm::length(again[i].eye - path[i].eye), 0.0, 1e-9);
    EXPECT_NEAR(glm::dot(again[i].forward(), path[i].forward()), 1.0, 1e-12);
    EXPECT_DOUBLE_EQ(again[i].near_dist, path[i].near_dist);
  }
}

// Section planes ride in the path's rows (four columns each after near and far): saved and read
// back exactly, normalised; a row with a partial plane or a seventh one is one named error.
TEST(CameraPath, SectionPlanesRoundTripAndBadOnesAreNamed) {
  auto path = load_camera_path("orbit:3", kBounds, kVp);
  path[1].sections.add({0, 0, 2, -1}, "test");
  path[1].sections.add({1, 0, 0, 5}, "test");
  const std::string f = write_tmp("cut.csv", "");
  save_camera_path(f, path);
  const auto again = load_camera_path(f, kBounds, kVp);
  ASSERT_EQ(again.size(), 3u);
  EXPECT_EQ(again[0].sections.count, 0);
  ASSERT_EQ(again[1].sections.count, 2);
  EXPECT_EQ(again[1].sections.planes[0].n, glm::dvec3(0, 0, 1));
  EXPECT_DOUBLE_EQ(again[1].sections.planes[0].d, -0.5);
  EXPECT_TRUE(again[1].sections == path[1].sections);
  std::string row = "0,0,1,5,0,0,0,0,1,0,60,0.1,100";
  EXPECT_NE(error_of(write_tmp("part.csv", row + ",1,0,0\n")).find("4 a section plane"), std::string::npos);
  EXPECT_NE(error_of(write_tmp("zero.csv", row + ",0,0,0,1\n")).find("non-zero finite normal"), std::string::npos);
  for (int k = 0; k < 7; ++k) row += ",0,1,0," + std::to_string(k);
  EXPECT_NE(error_of(write_tmp("seven.csv", row + "\n")).find("expected 11 or 13 columns"), std::string::npos);
}

// Sections::parse and the box tests culling uses: a box is removed only beyond the margin, kept
// whole only beyond it; Frustum::classify with the planes as cuts agrees.
TEST(Sections, ParseAndTheBoxTestsAreConservative) {
  EXPECT_EQ(Sections::parse("1,2,3,-4.5", "--x"), glm::dvec4(1, 2, 3, -4.5));
  for (const char* bad : {"1,2,3", "1,2,3,4,5", "a,0,0,1", "1,,0,1", "", "1,0,0,inf"})
    EXPECT_THROW(Sections::parse(bad, "--x"), InputError) << bad;
  Sections s;
  s.add({0, 1, 0, -2}, "t");  // keeps y >= 2
  const glm::dvec3 eye(0, 10, 0);
  Aabb below{{0, 0, 0}, {1, 1, 1}}, across{{0, 1, 0}, {1, 3, 1}}, above{{0, 3, 0}, {1, 4, 1}};
  Aabb touching{{0, 1, 0}, {1, 2, 1}};  // its top face on the plane: not surely removed
  EXPECT_TRUE(s.removes(below, eye));
  EXPECT_FALSE(s.removes(across, eye));
  EXPECT_FALSE(s.removes(touching, eye));
  EXPECT_TRUE(s.keeps_all(above, eye));
  EXPECT_FALSE(s.keeps_all(across, eye));
  Camera cam = Camera::look_at(eye, {0, 0, 0}, {0, 0, -1}, 60, 1, 0.1, 100);
  cam.sections = s;
  const Frustum fr = cam.frustum();
  EXPECT_EQ(fr.classify(below), Containment::Outside);
  EXPECT_NE(fr.classify(across), Containment::Outside);
  EXPECT_NE(fr.classify(across), Containment::Inside);
  Sections six;
  for (int k = 0; k < Sections::kMax; ++k) six.add({1, 0, 0, double(k)}, "t");
  EXPECT_THROW(six.add({1, 0, 0, 0}, "t"), InputError);
}

TEST(CameraPath, BadSpecsAndRowsNameTheProblem) {
  EXPECT_NE(error_of("walk:0").find("frame count"), std::string::npos);
  EXPECT_NE(error_of("orbit:x").find("frame count"), std::string::npos);
  EXPECT_NE(error_of("/nonexistent/p.csv").find("cannot open"), std::string::npos);
  std::string nan_row = write_tmp("nan.csv", "frame,eye_x\n0,0,1,nan,0,0,0,0,1,0,60\n");
  EXPECT_NE(error_of(nan_row).find("line 2: column eye_z: 'nan' is not a finite number"), std::string::npos) << error_of(nan_row);
  std::string short_row = write_tmp("short.csv", "0,0,1,2,0,0,0,0,1,0\n");
  EXPECT_NE(error_of(short_row).find("line 1: expected 11 or 13 columns, got 10"), std::string::npos);
  std::string order = write_tmp("order.csv", "0,0,1,5,0,0,0,0,1,0,60\n2,0,1,5,0,0,0,0,1,0,60\n");
  EXPECT_NE(error_of(order).find("line 2: frame 2 out of order"), std::string::npos);
  std::string same = write_tmp("same.csv", "0,1,1,1,1,1,1,0,1,0,60\n");
  EXPECT_NE(error_of(same).find("eye equals target"), std::string::npos);
  std::string near0 = write_tmp("near.csv", "0,0,1,5,0,0,0,0,1,0,60,0,100\n");
  EXPECT_NE(error_of(near0).find("line 1: near <= 0"), std::string::npos);
  std::string empty = write_tmp("empty.csv", "# nothing\n");
  EXPECT_NE(error_of(empty).find("no camera rows"), std::string::npos);
}
