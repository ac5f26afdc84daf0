// Runs the real frame_diff binary on temporary directories of PNG frames.
#include <gtest/gtest.h>

#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cstdio>
#include <filesystem>

#include "common/image.hpp"

using namespace occ;
namespace fs = std::filesystem;

namespace {

struct ToolRun {
  int exit_code;
  std::string output;  // stdout and stderr
};

ToolRun frame_diff(const std::string& args) {
  const std::string cmd = std::string(OCC_BIN_DIR) + "/frame_diff " + args + " 2>&1";
  FILE* pipe = popen(cmd.c_str(), "r");
  ToolRun r{-1, ""};
  if (!pipe) return r;
  std::array<char, 256> buf;
  while (size_t n = fread(buf.data(), 1, buf.size(), pipe)) r.output.append(buf.data(), n);
  int status = pclose(pipe);
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

Image solid(int w, int h, uint8_t v) {
  Image img;
  img.width = w;
  img.height = h;
  img.rgba.assign(size_t(w) * h * 4, v);
  return img;
}

class FrameDiff : public testing::Test {
 protected:
  void SetUp() override {
    root_ = fs::temp_directory_path() / ("occ_frame_diff_" + std::to_string(::getpid()) + "_" +
                                         testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(root_ / "a");
    fs::create_directories(root_ / "b");
    for (const char* dir : {"a", "b"}) {
      write_png((root_ / dir / "frame_00000.png").string(), solid(10, 10, 100));
      write_png((root_ / dir / "frame_00001.png").string(), solid(10, 10, 100));
    }
  }
  void TearDown() override { fs::remove_all(root_); }
  std::string a() const { return (root_ / "a").string(); }
  std::string b() const { return (root_ / "b").string(); }
  fs::path root_;
};

}  // namespace

TEST_F(FrameDiff, IdenticalFramesReportZero) {
  ToolRun r = frame_diff(a() + " " + b() + " --max-fraction 0");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("frame 00000: 0 differing pixels (0.0000%)"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("frames=2 differing_pixels=0 max_frame_fraction=0\n"), std::string::npos) << r.output;
}

TEST_F(FrameDiff, CountsPixelsAboveThresholdAndEnforcesMaxFraction) {
  Image img = solid(10, 10, 100);
  img.rgba[4 * 13 + 2] = 105;  // one pixel, one channel off by 5
  img.rgba[4 * 57 + 0] = 90;   // another off by 10
  write_png((root_ / "b" / "frame_00001.png").string(), img);
  ToolRun r = frame_diff(a() + " " + b());
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("frame 00001: 2 differing pixels (2.0000%)"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("frames=2 differing_pixels=2 max_frame_fraction=0.02\n"), std::string::npos) << r.output;
  r = frame_diff(a() + " " + b() + " --threshold 5");
  EXPECT_NE(r.output.find("differing_pixels=1 "), std::string::npos) << r.output;
  r = frame_diff(a() + " " + b() + " --threshold 10");
  EXPECT_NE(r.output.find("differing_pixels=0 "), std::string::npos) << r.output;
  EXPECT_EQ(frame_diff(a() + " " + b() + " --max-fraction 0.01").exit_code, 3);
  EXPECT_EQ(frame_diff(a() + " " + b() + " --max-fraction 0.02").exit_code, 0);
}

TEST_F(FrameDiff, MissingFrameOrSizeMismatchOrNoFramesFail) {
  fs::remove(root_ / "b" / "frame_00001.png");
  ToolRun r = frame_diff(a() + " " + b());
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.output.find("error: "), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("frame_00001.png: missing"), std::string::npos) << r.output;
  write_png((root_ / "b" / "frame_00001.png").string(), solid(10, 11, 100));
  r = frame_diff(a() + " " + b());
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.output.find("sizes differ"), std::string::npos) << r.output;
  fs::create_directories(root_ / "empty");
  EXPECT_EQ(frame_diff((root_ / "empty").string() + " " + b()).exit_code, 1);
}

TEST_F(FrameDiff, UsageErrorsExitTwo) {
  EXPECT_EQ(frame_diff("").exit_code, 2);
  EXPECT_EQ(frame_diff(a()).exit_code, 2);
  EXPECT_EQ(frame_diff(a() + " " + b() + " --threshold 256").exit_code, 2);
  EXPECT_EQ(frame_diff(a() + " " + b() + " --bogus").exit_code, 2);
  EXPECT_EQ(frame_diff(a() + " /nonexistent-dir").exit_code, 2);
  ToolRun help = frame_diff("--help");
  EXPECT_EQ(help.exit_code, 0);
  EXPECT_NE(help.output.find("usage: frame_diff DIR_A DIR_B"), std::string::npos) << help.output;
}
