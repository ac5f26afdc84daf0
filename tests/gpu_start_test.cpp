// The binaries start with only EGL present. No binary links OSMesa (and through it
// libLLVM) or Xlib; with OSMesa made unloadable (OCC_OSMESA_LIBRARY naming a file that does not
// exist) a render still goes through EGL with the same frames, and asking for OSMesa, or for a
// window without Xlib (OCC_X11_LIBRARY), fails with one error line naming the library. And the
// prepared GPU run (scripts/gpu_bundle.sh, run_gpu.sh) end to end on llvmpipe.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <cstdlib>
#include <iostream>
#include <map>
#include <sstream>

#include "integration_util.hpp"

using namespace occtest;
using namespace std::chrono_literals;

namespace {

const std::string kScene = "city:3x3:2:6:1";
const std::vector<std::string> kView = {"--width", "96", "--height", "64"};
const std::string kMissing = "/nonexistent/occ-missing-library.so";

// render_client (the reference renderer) ... with extra environment variables (NAME=VALUE) through env(1).
Outcome reference_with_env(const fs::path& out, const std::vector<std::string>& env,
                           const std::vector<std::string>& flags) {
  fs::create_directories(out);
  std::vector<std::string> a = {"/usr/bin/env"};
  a.insert(a.end(), env.begin(), env.end());
  for (const std::string& s : {bin("render_client"), std::string("--scene"), kScene,
                               std::string("--path"), std::string("walk:4"), std::string("--out"), out.string()})
    a.push_back(s);
  a.insert(a.end(), kView.begin(), kView.end());
  a.insert(a.end(), flags.begin(), flags.end());
  return run_to_end(a, out / "reference.log", 300s);
}

// The bundle ships release binaries under 60 MB; a sanitizer build's binaries and runtimes alone
// exceed that (51 MB of ASan binaries, 24 MB of libraries): nothing to test there.
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
constexpr bool kSanitizerBuild = true;
#else
constexpr bool kSanitizerBuild = false;
#endif

}  // namespace

TEST(GpuStart, NoBinaryLinksOsmesaLlvmOrXlib) {
  size_t checked = 0;
  for (const auto& e : fs::directory_iterator(OCC_BIN_DIR)) {
    struct stat st {};
    if (!e.is_regular_file() || ::stat(e.path().c_str(), &st) != 0 || !(st.st_mode & S_IXUSR)) continue;
    const fs::path log = fresh_dir("ldd") / (e.path().filename().string() + ".ldd");
    const Outcome o = run_to_end({"/usr/bin/ldd", e.path().string()}, log, 60s);
    ASSERT_EQ(o.code, 0) << e.path() << ": " << o.log;
    for (const char* lib : {"libOSMesa", "libLLVM", "libX11", "libxcb"})
      EXPECT_EQ(o.log.find(lib), std::string::npos) << e.path() << " links " << lib << ":\n" << o.log;
    ++checked;
  }
  for (const char* b : {"render_client", "switch_node", "occlusion_server", "frame_diff"})
    EXPECT_TRUE(fs::exists(bin(b))) << b;
  EXPECT_GE(checked, 4u);
}

TEST(GpuStart, WithoutOsmesaRendersThroughEglWithTheSameFrames) {
  const fs::path dir = fresh_dir("no_osmesa");
  const Outcome normal = reference_with_env(dir / "normal", {}, {});
  ASSERT_EQ(normal.code, 0) << normal.log;
  const Outcome egl_only = reference_with_env(dir / "egl_only", {"OCC_OSMESA_LIBRARY=" + kMissing}, {});
  ASSERT_EQ(egl_only.code, 0) << egl_only.log;
  // The start-up line: the renderer, its back end, GL_VERSION and the renderer class.
  EXPECT_NE(egl_only.log.find("GL_RENDERER "), std::string::npos) << egl_only.log;
  EXPECT_NE(egl_only.log.find("(egl-"), std::string::npos) << egl_only.log;
  EXPECT_NE(egl_only.log.find(", GL_VERSION "), std::string::npos) << egl_only.log;
  EXPECT_NE(egl_only.log.find(" renderer\n"), std::string::npos) << egl_only.log;
  EXPECT_EQ(frame_count(dir / "egl_only"), 4u);
  const Outcome d = frame_diff(dir / "normal", dir / "egl_only", {"--max-fraction", "0"});
  EXPECT_EQ(d.code, 0) << d.log;
  EXPECT_NE(diff_summary(d.log).find("differing_pixels=0 "), std::string::npos) << d.log;
}

TEST(GpuStart, OsmesaAskedForWithoutItFailsWithOneErrorNamingIt) {
  const fs::path dir = fresh_dir("osmesa_missing");
  expect_one_error(reference_with_env(dir, {"OCC_OSMESA_LIBRARY=" + kMissing}, {"--gl", "osmesa"}),
                   {"cannot load the OSMesa library " + kMissing, "OCC_OSMESA_LIBRARY", "libosmesa6"}, {.code = 1});
}

TEST(GpuStart, WindowWithoutXlibFailsWithOneErrorNamingIt) {
  const fs::path dir = fresh_dir("xlib_missing");
  // Any DISPLAY: the library is loaded before the display is opened.
  expect_one_error(reference_with_env(dir, {"OCC_X11_LIBRARY=" + kMissing, "DISPLAY=:99"}, {"--window"}),
                   {"--window: cannot load Xlib " + kMissing, "OCC_X11_LIBRARY", "libX11"}, {.code = 1});
}

// scripts/gpu_bundle.sh, then the bundle's run_gpu.sh end to end on llvmpipe in a
// folder that holds nothing else, with a bare environment (PATH without the build, no
// LD_LIBRARY_PATH, a fresh HOME), through the bundle's own libglvnd and glibc (--libs bundled):
// refused without --allow-software; with it, one table whose culling methods and cluster have no
// wrong pixels against brute force.
TEST(GpuBundle, RunsEndToEndOnASoftwareRenderer) {
  if (kSanitizerBuild) GTEST_SKIP() << "a sanitizer build: its binaries are not what the bundle ships";
  const fs::path dir = fresh_dir("gpu_bundle");
  const fs::path bundle = dir / "bundle", home = dir / "home", work = dir / "work";
  fs::create_directories(home);
  fs::create_directories(work);
  auto bare = [&](const std::vector<std::string>& env, const std::vector<std::string>& cmd) {
    std::vector<std::string> a = {"/usr/bin/env", "-i", "PATH=/usr/bin:/bin", "HOME=" + home.string(), "LP_NUM_THREADS=0"};
    // The sanitizer suite's settings (its leak suppressions for Mesa) belong to the test, not to
    // the machine the bundle models.
    for (const char* v : {"ASAN_OPTIONS", "LSAN_OPTIONS", "UBSAN_OPTIONS", "TSAN_OPTIONS"})
      if (const char* value = std::getenv(v)) a.push_back(std::string(v) + "=" + value);
    a.insert(a.end(), env.begin(), env.end());
    a.insert(a.end(), cmd.begin(), cmd.end());
    return a;
  };
  const Outcome made = run_to_end(bare({std::string("OCC_BIN=") + OCC_BIN_DIR, std::string("OCC_SHARED_DIR=") + OCC_SHARED_DIR},
                                       {"/bin/bash", std::string(OCC_SOURCE_DIR) + "/scripts/gpu_bundle.sh", bundle.string()}),
                                  dir / "bundle.log", 120s);
  ASSERT_EQ(made.code, 0) << made.log;
  uintmax_t bytes = 0;
  for (const auto& e : fs::recursive_directory_iterator(bundle)) {
    if (!e.is_regular_file()) continue;
    bytes += e.file_size();
    const std::string name = e.path().filename().string();
    for (const char* lib : {"libOSMesa", "libLLVM", "libX11", "libEGL_nvidia", "libEGL_mesa"})
      EXPECT_EQ(name.find(lib), std::string::npos) << e.path();
  }
  EXPECT_LT(bytes, 60u << 20);
  for (const char* f : {"run_gpu.sh", "bin/render_client", "bin/switch_node", "bin/frame_diff", "scripts/cluster.sh",
                        "lib/glvnd/libEGL.so.1", "lib/glibc/libc.so.6", "lib/libstdc++.so.6"})
    EXPECT_TRUE(fs::exists(bundle / f)) << f;
  const std::string run_gpu = (bundle / "run_gpu.sh").string();

  const Outcome refused = run_to_end(bare({}, {run_gpu, "--quick", "--out", (work / "refused").string()}),
                                     dir / "refused.log", 120s);
  expect_one_error(refused, {"software renderer, not a GPU", "--allow-software"}, {.code = 1});

  const Outcome ran = run_to_end(
      bare({}, {run_gpu, "--allow-software", "--quick", "--libs", "bundled", "--out", (work / "run").string()}),
      dir / "run.log", 600s);
  ASSERT_EQ(ran.code, 0) << ran.log;
  EXPECT_NE(ran.log.find("libraries: the bundle's, its libglvnd, its glibc"), std::string::npos) << ran.log;
  const std::string table = read_file(work / "run" / "table.txt");
  std::cout << table;
  std::map<std::string, std::vector<std::string>> rows;  // method -> the row's last six columns
  std::istringstream in(table);
  for (std::string line; std::getline(in, line);) {
    if (line.rfind("plant:1 ", 0) != 0) continue;
    std::istringstream words(line);
    std::vector<std::string> w;
    for (std::string x; words >> x;) w.push_back(x);
    ASSERT_GE(w.size(), 9u) << line;
    std::string method;
    for (size_t i = 2; i + 6 < w.size(); ++i) method += (method.empty() ? "" : " ") + w[i];
    rows[method] = std::vector<std::string>(w.end() - 6, w.end());
  }
  ASSERT_EQ(rows.size(), 4u) << table;
  EXPECT_EQ(rows["brute force"][3], "-") << table;
  for (const char* m : {"frustum", "chc", "cluster (3 proc)"}) {
    ASSERT_TRUE(rows.count(m)) << m << "\n" << table;
    EXPECT_EQ(rows[m][3], "0") << m << ": wrong pixels\n" << table;
    EXPECT_NE(rows[m][0], "n/a") << m << "\n" << table;
    EXPECT_NE(rows[m][5], "n/a") << m << "\n" << table;
  }
}

// The bundle stays under 60 MB whatever the shared folder holds: a scene that would push it over
// is left out and named, and a scene folder's other files (caches, temporaries) are not copied.
TEST(GpuBundle, LeavesOutSceneFilesOverItsLimitAndNamesThem) {
  if (kSanitizerBuild) GTEST_SKIP() << "a sanitizer build: its binaries are not what the bundle ships";
  const fs::path dir = fresh_dir("gpu_bundle_limit");
  const fs::path shared = dir / "shared", bundle = dir / "bundle";
  auto write = [](const fs::path& p, size_t bytes, char c) {
    fs::create_directories(p.parent_path());
    std::ofstream(p, std::ios::binary) << std::string(bytes, c);
  };
  write(shared / "scenes/small/small.gltf", 1000, ' ');
  write(shared / "scenes/small/small.bin", 1u << 20, 'a');
  write(shared / "scenes/small/small.lod.tmp", 2u << 20, 'b');  // not a scene file
  write(shared / "scenes/huge/huge.glb", 70u << 20, 'c');
  const Outcome made = run_to_end({"/usr/bin/env", std::string("OCC_BIN=") + OCC_BIN_DIR, "OCC_SHARED_DIR=" + shared.string(),
                                   "/bin/bash", std::string(OCC_SOURCE_DIR) + "/scripts/gpu_bundle.sh", bundle.string()},
                                  dir / "bundle.log", 120s);
  ASSERT_EQ(made.code, 0) << made.log;
  EXPECT_NE(made.log.find("left out to stay under 60 MB: huge (70 MB)"), std::string::npos) << made.log;
  EXPECT_TRUE(fs::exists(bundle / "scenes/small/small.gltf"));
  EXPECT_TRUE(fs::exists(bundle / "scenes/small/small.bin"));
  EXPECT_FALSE(fs::exists(bundle / "scenes/small/small.lod.tmp"));
  EXPECT_FALSE(fs::exists(bundle / "scenes/huge"));
  uintmax_t bytes = 0;
  for (const auto& e : fs::recursive_directory_iterator(bundle))
    if (e.is_regular_file()) bytes += e.file_size();
  EXPECT_LT(bytes, 60u << 20);
}
