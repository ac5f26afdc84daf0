// Runs the real frame_diff binary on temporary directories of PNG frames.
#include <gtest/gtest.h>

#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>

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

// --items (the tau checker, render_client/tools/item_diff.hpp): item buffers and items.txt written
// by hand; a 4 x 4 square of item 0 moved right by 3 pixels in B.
class FrameDiffItems : public FrameDiff {
 protected:
  // Item 0 (value 1) at [x0, x0 + 4) x [2, 6) of 12 x 8; as depth: 0.5f there (bits 0x3f000000).
  static Image square(int x0, bool depth) {
    Image img = solid(12, 8, 0);
    for (int y = 2; y < 6; ++y)
      for (int x = x0; x < x0 + 4; ++x) img.rgba[4 * size_t(y * 12 + x) + (depth ? 3 : 0)] = depth ? 0x3f : 1;
    return img;
  }
  void write(const std::string& dir, int x0, bool space = true) {
    write_png((root_ / dir / "items_00000.png").string(), square(x0, false));
    write_png((root_ / dir / "depth_00000.png").string(), square(x0, true));
    if (space) std::ofstream(root_ / dir / "items.txt") << "occswitch item buffer ids 1\nitems 1 nodes 1\n0 1\n";
  }
};

TEST_F(FrameDiffItems, ReportsTheDisplacementAndChecksThePromise) {
  write("a", 2);
  write("b", 5);
  ToolRun r = frame_diff(a() + " " + b() + " --items --tau 1");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("frames=1 objects_missing=0 max_displacement=3.000"), std::string::npos) << r.output;
  EXPECT_EQ(frame_diff(a() + " " + b() + " --items --tau 1 --check").exit_code, 3);  // 3 > 1 + 1
  EXPECT_EQ(frame_diff(a() + " " + b() + " --items --tau 2 --check").exit_code, 0);  // 3 <= 2 + 1
  EXPECT_EQ(frame_diff(a() + " " + b() + " --items --tau 1 --slack 2 --check").exit_code, 0);
  write("b", 0, true);
  write_png((root_ / "b" / "items_00000.png").string(), solid(12, 8, 0));  // drew nothing
  r = frame_diff(a() + " " + b() + " --items --tau 5 --check");
  EXPECT_EQ(r.exit_code, 3) << r.output;
  EXPECT_NE(r.output.find("objects_missing=1"), std::string::npos) << r.output;
}

TEST_F(FrameDiffItems, NeedsTheIdSpaceOfBothRuns) {
  write("a", 2);
  write("b", 2, false);
  ToolRun r = frame_diff(a() + " " + b() + " --items");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("items.txt"), std::string::npos) << r.output;
}
