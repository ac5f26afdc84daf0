// Issue 17 item 4/5: --version everywhere (one version, the VERSION file), script --help prints
// help without installing or building, and scripts/video.sh makes an MP4 (skipped without ffmpeg).
#include <gtest/gtest.h>

#include "integration_util.hpp"

using namespace occtest;
using namespace std::chrono_literals;

namespace {
std::string version() {
  std::string v = read_file(std::string(OCC_SOURCE_DIR) + "/VERSION");
  return v.substr(0, v.find('\n'));
}
std::string script(const std::string& name) { return std::string(OCC_SOURCE_DIR) + "/scripts/" + name; }
}  // namespace

TEST(Conventions, EveryBinaryAndScriptHasTheSameVersion) {
  const fs::path dir = fresh_dir("version");
  ASSERT_FALSE(version().empty());
  for (const char* b : {"render_client", "switch_node", "occlusion_server", "frame_diff", "cull_overview", "link_relay"}) {
    Proc p({bin(b), "--version"}, dir / (std::string(b) + ".log"));
    EXPECT_EQ(p.wait(30s), 0) << b << ": " << p.log();
    EXPECT_EQ(p.log().rfind(std::string(b) + " (occswitch) " + version(), 0), 0u) << p.log();
  }
  for (const char* s : {"run.sh", "build.sh", "test.sh", "setup.sh", "cluster.sh", "bench.sh", "netlab.sh",
                        "accuracy_sweep.sh", "video.sh"}) {
    Proc p({"/bin/bash", script(s), "--version"}, dir / (std::string(s) + ".log"));
    EXPECT_EQ(p.wait(30s), 0) << s << ": " << p.log();
    EXPECT_EQ(p.log(), std::string(s) + " (occswitch) " + version() + "\n");
  }
}

TEST(Conventions, ScriptHelpIsHelpAndDoesNothingElse) {
  const fs::path dir = fresh_dir("help");
  for (const char* s : {"run.sh", "build.sh", "test.sh", "setup.sh", "cluster.sh", "video.sh"}) {
    Proc p({"/bin/bash", script(s), "--help"}, dir / (std::string(s) + ".log"));
    EXPECT_EQ(p.wait(30s), 0) << s << ": " << p.log();
    const std::string out = p.log();
    EXPECT_GT(out.size(), 20u) << s;
    EXPECT_EQ(out.find("#!/"), std::string::npos) << s << " printed its source: " << out;
    EXPECT_EQ(out.find("set -"), std::string::npos) << s << " printed its source: " << out;
    EXPECT_EQ(out.find("setup:"), std::string::npos) << s << " ran setup: " << out;
  }
}

TEST(Conventions, VideoFromFrames) {
  if (!fs::exists("/usr/bin/ffmpeg")) GTEST_SKIP() << "needs ffmpeg (Debian package ffmpeg): not installed";
  const fs::path dir = fresh_dir("video");
  Proc r({bin("render_client"), "--reference", "--scene", "city:2x2:2:4:1", "--path", "walk:12", "--width", "65",
          "--height", "49", "--out", (dir / "f").string()},
         dir / "render.log");
  ASSERT_EQ(r.wait(60s), 0) << r.log();
  Proc v({"/bin/bash", script("video.sh"), (dir / "f").string(), "--fps", "12"}, dir / "video.log");
  ASSERT_EQ(v.wait(60s), 0) << v.log();
  EXPECT_NE(v.log().find("12 frames at 12 fps"), std::string::npos) << v.log();
  ASSERT_TRUE(fs::exists(dir / "f" / "video.mp4"));
  const std::string mp4 = read_file(dir / "f" / "video.mp4");
  EXPECT_GT(mp4.size(), 1000u);
  EXPECT_NE(mp4.find("ftyp"), std::string::npos);  // an MP4 container
  Proc none({"/bin/bash", script("video.sh"), dir.string()}, dir / "none.log");
  EXPECT_EQ(none.wait(30s), 2);
  EXPECT_NE(none.log().find("has no frame_NNNNN.png"), std::string::npos) << none.log();
}
