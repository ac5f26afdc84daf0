// --version everywhere (one version, the VERSION file), script --help prints
// help without installing or building, and scripts/video.sh makes an MP4 (skipped without ffmpeg).
#include <gtest/gtest.h>

#include <sched.h>

#include <algorithm>
#include <fstream>
#include <map>
#include <memory>
#include <set>
#include <sstream>
#include <stdexcept>
#include <thread>
#include <vector>

#include "common/memory.hpp"
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
  for (const char* b : {"render_client", "switch_node", "occlusion_server", "frame_diff", "cull_overview", "link_relay",
                        "scene_export"}) {
    Proc p({bin(b), "--version"}, dir / (std::string(b) + ".log"));
    EXPECT_EQ(p.wait(30s), 0) << b << ": " << p.log();
    EXPECT_EQ(p.log().rfind(std::string(b) + " (occswitch) " + version(), 0), 0u) << p.log();
  }
  for (const char* s : {"run.sh", "build.sh", "test.sh", "setup.sh", "cluster.sh", "cluster_rank.sh",
                        "cluster_hosts.sh", "bench.sh", "netlab.sh", "accuracy_sweep.sh", "video.sh", "scale_matrix.sh",
                        "gpu_bundle.sh", "run_gpu.sh"}) {
    Proc p({"/bin/bash", script(s), "--version"}, dir / (std::string(s) + ".log"));
    EXPECT_EQ(p.wait(30s), 0) << s << ": " << p.log();
    EXPECT_EQ(p.log(), std::string(s) + " (occswitch) " + version() + "\n");
  }
}

namespace {
// A binary's --help as heading -> its flags (--help and --version left out), headings in order.
std::vector<std::pair<std::string, std::vector<std::string>>> help_groups(const std::string& binary,
                                                                           const fs::path& log) {
  Proc p({bin(binary), "--help"}, log);
  EXPECT_EQ(p.wait(30s), 0) << binary << ": " << p.log();
  std::vector<std::pair<std::string, std::vector<std::string>>> groups;
  std::istringstream in(p.log());
  for (std::string line; std::getline(in, line);) {
    if (!line.empty() && line.back() == ':' && line[0] != ' ' && line.rfind("usage", 0) != 0) {
      groups.push_back({line.substr(0, line.size() - 1), {}});
    } else if (line.rfind("  --", 0) == 0) {
      const std::string flag = line.substr(2, line.find(' ', 2) - 2);
      if (flag != "--help" && flag != "--version" && !groups.empty()) groups.back().second.push_back(flag);
    }
  }
  return groups;
}
size_t flag_count(const std::vector<std::pair<std::string, std::vector<std::string>>>& g) {
  size_t n = 0;
  for (const auto& [heading, flags] : g) n += flags.size();
  return n;
}
}  // namespace

// The knobs a user needs, grouped: --help sorts them under the same five headings in the same
// order everywhere; switch_node has at most 20 flags and render_client at most 24; cull_overview
// replays the nodes' culling, so it takes every scene, accuracy and expert flag of switch_node.
TEST(Conventions, HelpIsGroupedAndTheFlagsAreFew) {
  const fs::path dir = fresh_dir("help_groups");
  const std::vector<std::string> order = {"scene and path", "output", "cluster and network", "accuracy", "expert"};
  std::map<std::string, std::vector<std::pair<std::string, std::vector<std::string>>>> help;
  for (const char* b : {"switch_node", "render_client", "cull_overview"}) {
    help[b] = help_groups(b, dir / (std::string(b) + ".log"));
    size_t at = 0;
    for (const auto& [heading, flags] : help[b]) {
      const auto it = std::find(order.begin() + long(at), order.end(), heading);
      ASSERT_NE(it, order.end()) << b << ": heading '" << heading << "' unknown or out of order";
      at = size_t(it - order.begin()) + 1;
      EXPECT_FALSE(flags.empty()) << b << ": " << heading;
    }
  }
  EXPECT_LE(flag_count(help["switch_node"]), 20u);
  EXPECT_LE(flag_count(help["render_client"]), 24u);
  std::set<std::string> overview;
  for (const auto& [heading, flags] : help["cull_overview"]) overview.insert(flags.begin(), flags.end());
  for (const auto& [heading, flags] : help["switch_node"])
    if (heading != "cluster and network") {
      for (const std::string& f : flags) EXPECT_TRUE(overview.count(f)) << "cull_overview lacks switch_node's " << f;
    }
}

TEST(Conventions, ScriptHelpIsHelpAndDoesNothingElse) {
  const fs::path dir = fresh_dir("help");
  for (const char* s : {"run.sh", "build.sh", "test.sh", "setup.sh", "cluster.sh", "cluster_rank.sh",
                        "cluster_hosts.sh", "video.sh", "bench.sh", "netlab.sh", "accuracy_sweep.sh", "recovery.sh",
                        "scale_matrix.sh", "spikes_matrix.sh", "gpu_bundle.sh", "run_gpu.sh"}) {
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
  Proc r({bin("render_client"), "--scene", "city:2x2:2:4:1", "--path", "walk:12", "--width", "65",
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

// scripts/cluster.sh names the failing process with its own error line, and stops the others at
// once instead of letting them wait for it until the nodes' --timeout-ms.
namespace {
std::vector<std::string> cluster(const fs::path& out, std::vector<std::string> extra) {
  std::vector<std::string> a = {"/bin/bash", script("cluster.sh"), "--out", out.string(), "--width", "64", "--height", "48"};
  a.insert(a.end(), extra.begin(), extra.end());
  return a;
}
}  // namespace

TEST(Conventions, ClusterPrintsTheFailingProcessesOwnError) {
  const fs::path dir = fresh_dir("cluster_errors");
  {  // a missing scene: node 0's own line, naming the file
    Proc p(cluster(dir / "a", {"--scene", (dir / "no_such_scene.gltf").string()}), dir / "a.log");
    EXPECT_NE(p.wait(120s), 0);
    const std::string log = p.log();
    EXPECT_NE(log.find("cluster: node0 exited before listening"), std::string::npos) << log;
    EXPECT_NE(log.find("  error: " + (dir / "no_such_scene.gltf").string() + ": cannot open file"), std::string::npos)
        << log;
  }
  {  // a bad flag (passed to all three): node 0 says which
    Proc p(cluster(dir / "b", {"--scene", "city:2x2:2:4:1", "--no-such-flag", "1"}), dir / "b.log");
    EXPECT_NE(p.wait(120s), 0);
    const std::string log = p.log();
    EXPECT_NE(log.find("cluster: node0 exited before listening"), std::string::npos) << log;
    EXPECT_NE(log.find("  error:"), std::string::npos) << log;
    EXPECT_NE(log.find("--no-such-flag"), std::string::npos) << log;
  }
  {  // a missing --path file: said before any process starts
    Proc p(cluster(dir / "c", {"--scene", "city:2x2:2:4:1", "--path", (dir / "no_such_path.csv").string()}),
           dir / "c.log");
    EXPECT_EQ(p.wait(60s), 2);
    const std::string log = p.log();
    EXPECT_NE(log.find("no_such_path.csv': cannot open camera path file"), std::string::npos) << log;
    EXPECT_FALSE(fs::exists(dir / "c" / "node0.log")) << log;
  }
  {  // a bad --node-raster-threads: said before any process starts
    Proc p(cluster(dir / "e", {"--scene", "city:2x2:2:4:1", "--node-raster-threads", "two"}), dir / "e.log");
    EXPECT_EQ(p.wait(60s), 2);
    EXPECT_NE(p.log().find("--node-raster-threads 'two': expected a whole number from 0 to 64"), std::string::npos)
        << p.log();
    EXPECT_FALSE(fs::exists(dir / "e" / "node0.log")) << p.log();
  }
  {  // a bad --client-raster-threads: said before any process starts
    Proc p(cluster(dir / "g", {"--scene", "city:2x2:2:4:1", "--client-raster-threads", "-1"}), dir / "g.log");
    EXPECT_EQ(p.wait(60s), 2);
    EXPECT_NE(p.log().find("--client-raster-threads '-1': expected auto or a whole number from 0 to 64"),
              std::string::npos)
        << p.log();
    EXPECT_FALSE(fs::exists(dir / "g" / "node0.log")) << p.log();
  }
  {  // a bad --pin-nodes: said before any process starts
    Proc p(cluster(dir / "f", {"--scene", "city:2x2:2:4:1", "--pin-nodes", "always"}), dir / "f.log");
    EXPECT_EQ(p.wait(60s), 2);
    EXPECT_NE(p.log().find("--pin-nodes 'always': expected auto, on or off"), std::string::npos) << p.log();
    EXPECT_FALSE(fs::exists(dir / "f" / "node0.log")) << p.log();
  }
  {  // a broken --path file: the render client's own line, and the nodes are stopped at once, not
     // left to wait for it until their --timeout-ms
    std::ofstream(dir / "broken.csv") << "frame,eye_x\n0,1\n";
    Proc p(cluster(dir / "d", {"--scene", "city:2x2:2:4:1", "--path", (dir / "broken.csv").string(),
                               "--timeout-ms", "600000"}),
           dir / "d.log");
    EXPECT_NE(p.wait(300s), 0);
    const std::string log = p.log();
    EXPECT_NE(log.find("cluster: render_client exited with status 2"), std::string::npos) << log;
    EXPECT_NE(log.find("  error: " + (dir / "broken.csv").string() + ": line 2: expected 11 or 13 columns"),
              std::string::npos) << log;
    EXPECT_NE(log.find("cluster: stopping node0 node1"), std::string::npos) << log;
  }
}

namespace {
// /proc/PID/status's Cpus_allowed_list ("0-1", "1"), empty when the process is gone.
std::string cpus_allowed(const std::string& pid) {
  std::ifstream f("/proc/" + pid + "/status");
  for (std::string line; std::getline(f, line);)
    if (line.rfind("Cpus_allowed_list:", 0) == 0) return line.substr(line.find_first_not_of(" \t", 18));
  return "";
}
// The file name of process `pid`'s program ("" where it is gone).
std::string program_of(const std::string& pid) {
  std::error_code ec;
  return fs::read_symlink("/proc/" + pid + "/exe", ec).filename().string();
}
// Process `pid`'s LP_NUM_THREADS ("unset" where it has none): the environment its program
// started with.
std::string lp_threads(const std::string& pid) {
  std::ifstream f("/proc/" + pid + "/environ");
  for (std::string var; std::getline(f, var, '\0');)
    if (var.rfind("LP_NUM_THREADS=", 0) == 0) return var.substr(15);
  return "unset";
}
}  // namespace

// --pin-nodes on: both switch nodes may run on the launcher's last CPU only, the render client on
// all of them; off: the nodes too. (auto is on under 4 CPUs.) The render client's rasteriser
// threads (--client-raster-threads auto): none where the nodes are pinned, else
// $LP_NUM_THREADS (3 here); the nodes' 0 (--node-raster-threads) either way.
TEST(Conventions, ClusterPinsBothNodesToItsLastCpu) {
  cpu_set_t set;
  CPU_ZERO(&set);
  ASSERT_EQ(::sched_getaffinity(0, sizeof set, &set), 0);
  int count = 0, last = -1;
  for (int c = 0; c < CPU_SETSIZE; ++c)
    if (CPU_ISSET(c, &set)) ++count, last = c;
  if (count < 2) GTEST_SKIP() << "one CPU: nothing to pin apart";
  const std::string all = cpus_allowed("self");
  const fs::path dir = fresh_dir("cluster_pin");
  for (const std::string mode : {"on", "off"}) {
    std::vector<std::string> args = {"/usr/bin/env", "LP_NUM_THREADS=3"};
    for (const std::string& a :
         cluster(dir / mode, {"--scene", "city:2x2:2:4:1", "--path", "walk:8000", "--images", "off", "--pin-nodes", mode}))
      args.push_back(a);
    Proc p(args, dir / (mode + ".log"));
    // Each process's CPUs, read while it runs (the nodes from their start, the client once
    // it is started: it runs for seconds).
    std::string seen[3], threads[3];
    const char* names[3] = {"node0", "node1", "render_client"};
    const auto until = std::chrono::steady_clock::now() + 120s;
    while (std::chrono::steady_clock::now() < until && p.running() && seen[2].empty()) {
      for (int k = 0; k < 3; ++k) {
        // A node's pid file is written as it is started (by taskset, which then runs it): its
        // port file says it runs.
        const fs::path pid = dir / mode / (std::string(names[k]) + ".pid");
        const bool started = k == 2 || fs::exists(dir / mode / (std::string(names[k]) + ".port"));
        if (seen[k].empty() && started && fs::exists(pid)) {
          std::string id = read_file(pid);
          id.erase(id.find_last_not_of(" \n") + 1);
          // Once the pid runs the program itself (before, a shell or taskset about to start it:
          // the launcher's environment, not the one it gives the program) and its environment
          // reads back (cluster.sh sets LP_NUM_THREADS for all three; mid-exec it reads empty).
          const std::string threads_now = id.empty() ? "unset" : lp_threads(id);
          if (program_of(id) == (k == 2 ? "render_client" : "switch_node") && threads_now != "unset")
            seen[k] = cpus_allowed(id), threads[k] = threads_now;
        }
      }
      std::this_thread::sleep_for(5ms);
    }
    EXPECT_EQ(p.wait(300s), 0) << p.log();
    const std::string nodes = mode == "on" ? std::to_string(last) : all;
    EXPECT_EQ(seen[0], nodes) << "--pin-nodes " << mode << ": node 0";
    EXPECT_EQ(seen[1], nodes) << "--pin-nodes " << mode << ": node 1";
    EXPECT_EQ(seen[2], all) << "--pin-nodes " << mode << ": the render client";
    EXPECT_EQ(threads[0], "0") << "--pin-nodes " << mode << ": node 0";
    EXPECT_EQ(threads[2], mode == "on" ? "0" : "3") << "--pin-nodes " << mode << ": the render client";
    EXPECT_EQ(p.log().find("both switch nodes on CPU") != std::string::npos, mode == "on") << p.log();
    EXPECT_EQ(p.log().find("with 0 rasteriser threads") != std::string::npos, mode == "on") << p.log();
  }
}

namespace {
// Where this machine makes CPU groups (scripts/lib.sh occ_cpu_groups_root): cgroup v1's cpu
// hierarchy, or v2 with the cpu controller; "" where neither.
std::string cpu_groups_root() {
  if (fs::exists("/sys/fs/cgroup/cpu/cpu.cfs_quota_us")) return "/sys/fs/cgroup/cpu";
  if (fs::exists("/sys/fs/cgroup/cgroup.controllers") &&
      (" " + read_file("/sys/fs/cgroup/cgroup.controllers")).find(" cpu") != std::string::npos)
    return "/sys/fs/cgroup";
  return "";
}
// Process `pid`'s CPU group, relative to that root ("" where it is gone): v1's line for a
// hierarchy whose controllers include cpu ("1:cpu:/a/b" or "1:cpu,cpuacct:/a/b"), else v2's "0::/a/b".
std::string cpu_group_of(const std::string& pid) {
  std::ifstream f("/proc/" + pid + "/cgroup");
  std::string v2;
  for (std::string line; std::getline(f, line);) {
    const size_t a = line.find(':'), b = line.find(':', a + 1);
    if (a == std::string::npos || b == std::string::npos) continue;
    const std::string controllers = "," + line.substr(a + 1, b - a - 1) + ",";
    if (controllers.find(",cpu,") != std::string::npos) return line.substr(b + 1);
    if (controllers == ",,") v2 = line.substr(b + 1);
  }
  return v2;
}
// A group's CPU quota as "QUOTA PERIOD" (microseconds), v1 or v2.
std::string cpu_quota(const fs::path& group) {
  auto first_line = [](const fs::path& p) {
    std::string s = read_file(p);
    return s.substr(0, s.find('\n'));
  };
  if (fs::exists(group / "cpu.max")) return first_line(group / "cpu.max");
  return first_line(group / "cpu.cfs_quota_us") + " " + first_line(group / "cpu.cfs_period_us");
}
}  // namespace

// --host-cpus 0.5: node 0, node 1 and the render client each in a CPU group of its own with half a
// core's time (a 1 ms quota per 2 ms period), none pinned, the render client with $LP_NUM_THREADS
// rasteriser threads as on a host of its own; the groups are gone after the run (stopped by
// Ctrl-C). Bad values are one error.
TEST(Conventions, ClusterHostCpusGivesEachProcessCpuTimeOfItsOwn) {
  const fs::path dir = fresh_dir("cluster_host_cpus");
  for (const std::string bad : {"0", "abc", "1e3", "-1", "99"}) {
    Proc p(cluster(dir / "bad", {"--scene", "city:2x2:2:4:1", "--host-cpus", bad}), dir / "bad.log");
    EXPECT_EQ(p.wait(30s), 2) << p.log();
    EXPECT_NE(p.log().find("error: --host-cpus '" + bad + "': expected a number of cores from 0.05 to "),
              std::string::npos)
        << p.log();
  }
  Proc both(cluster(dir / "bad", {"--scene", "city:2x2:2:4:1", "--host-cpus", "0.5", "--pin-nodes", "on"}),
            dir / "both.log");
  EXPECT_EQ(both.wait(30s), 2) << both.log();
  EXPECT_NE(both.log().find("error: --pin-nodes on: not with --host-cpus"), std::string::npos) << both.log();
  // One machine only: not over ssh, not per rank under a job launcher.
  Proc hosts({"/bin/bash", script("cluster.sh"), "--hosts", "a,b,c", "--scene", "city", "--host-cpus", "0.5"},
             dir / "hosts.log");
  EXPECT_EQ(hosts.wait(30s), 2) << hosts.log();
  EXPECT_NE(hosts.log().find("error: --host-cpus runs on one machine: not with --hosts"), std::string::npos)
      << hosts.log();
  Proc rank({"/bin/bash", script("cluster_rank.sh"), "--rank", "0", "--scene", "city", "--host-cpus", "0.5"},
            dir / "rank.log");
  EXPECT_EQ(rank.wait(30s), 2) << rank.log();
  EXPECT_NE(rank.log().find("error: --host-cpus is a scripts/cluster.sh option (one machine)"), std::string::npos)
      << rank.log();

  const std::string root = cpu_groups_root();
  if (::geteuid() != 0 || root.empty()) GTEST_SKIP() << "needs root and a cgroup CPU controller";
  const std::string all = cpus_allowed("self");
  std::vector<std::string> args = {"/usr/bin/env", "LP_NUM_THREADS=3"};
  for (const std::string& a : cluster(dir / "run", {"--scene", "city:2x2:2:4:1", "--path", "walk:8000",
                                                     "--images", "off", "--host-cpus", "0.5"}))
    args.push_back(a);
  Proc p(args, dir / "run.log");
  std::string group[3], quota[3], cpus[3], threads[3];
  const char* names[3] = {"node0", "node1", "render_client"};
  const auto until = std::chrono::steady_clock::now() + 120s;
  while (std::chrono::steady_clock::now() < until && p.running() && group[2].empty()) {
    for (int k = 0; k < 3; ++k) {
      const fs::path pid = dir / "run" / (std::string(names[k]) + ".pid");
      const bool started = k == 2 || fs::exists(dir / "run" / (std::string(names[k]) + ".port"));
      if (!group[k].empty() || !started || !fs::exists(pid)) continue;
      std::string id = read_file(pid);
      id.erase(id.find_last_not_of(" \n") + 1);
      // Once the pid runs the program itself (before: the shell that puts it in its group).
      if (id.empty() || program_of(id) != (k == 2 ? "render_client" : "switch_node")) continue;
      const std::string g = cpu_group_of(id), t = lp_threads(id);
      if (g.empty() || t == "unset") continue;
      group[k] = g, cpus[k] = cpus_allowed(id), threads[k] = t;
      quota[k] = cpu_quota(fs::path(root + g));
    }
    std::this_thread::sleep_for(5ms);
  }
  // Ctrl-C (SIGTERM) once all three were seen: the groups go with the processes.
  p.signal(SIGTERM);
  const int code = p.wait(120s);
  EXPECT_TRUE(code == 130 || code == 0) << code << ": " << p.log();
  for (int k = 0; k < 3; ++k) {
    EXPECT_EQ(fs::path(group[k]).filename().string(), names[k]) << group[k];
    EXPECT_EQ(fs::path(group[k]).parent_path().filename().string().rfind("occswitch-cluster-", 0), 0u) << group[k];
    EXPECT_EQ(fs::path(group[k]).parent_path(), fs::path(group[0]).parent_path()) << group[k];
    EXPECT_EQ(quota[k], "1000 2000") << names[k];
    EXPECT_EQ(cpus[k], all) << names[k] << ": not pinned";
  }
  EXPECT_EQ(threads[0], "0");
  EXPECT_EQ(threads[2], "3");
  EXPECT_NE(p.log().find("each in a CPU group of 0.5 cores (--host-cpus)"), std::string::npos) << p.log();
  if (!group[0].empty()) {
    EXPECT_FALSE(fs::exists(root + fs::path(group[0]).parent_path().string())) << "left behind";
  }
}

TEST(Conventions, NetlabTakesCameraModeAsEverywhere) {
  const fs::path dir = fresh_dir("netlab_flags");
  Proc p({"/bin/bash", script("netlab.sh"), "--scene", "city", "--mode", "latest"}, dir / "mode.log");
  EXPECT_EQ(p.wait(30s), 2);
  EXPECT_NE(p.log().find("--mode is now --camera-mode"), std::string::npos) << p.log();
  Proc q({"/bin/bash", script("netlab.sh"), "--scene", "city", "--camera-mode", "sometimes"}, dir / "cm.log");
  EXPECT_EQ(q.wait(30s), 2);
  EXPECT_NE(q.log().find("--camera-mode 'sometimes': expected latest or lockstep"), std::string::npos) << q.log();
}

// One default viewport: every script that renders defaults to the binaries' 512x512 (lib.sh), and
// the binaries' --help says 512.
TEST(Conventions, OneDefaultViewport) {
  const std::string lib = read_file(script("lib.sh"));
  EXPECT_NE(lib.find("OCC_WIDTH=512 OCC_HEIGHT=512"), std::string::npos);
  for (const char* s : {"bench.sh", "netlab.sh", "accuracy_sweep.sh"}) {
    const std::string text = read_file(script(s));
    EXPECT_NE(text.find("width=$OCC_WIDTH height=$OCC_HEIGHT"), std::string::npos) << s;
  }
  for (const char* s : {"cluster.sh", "run.sh"}) EXPECT_EQ(read_file(script(s)).find("--width 6"), std::string::npos) << s;
  const fs::path dir = fresh_dir("viewport");
  for (const char* b : {"render_client", "switch_node", "occlusion_server"}) {
    Proc p({bin(b), "--help"}, dir / (std::string(b) + ".log"));
    EXPECT_EQ(p.wait(30s), 0) << p.log();
    EXPECT_NE(p.log().find("512"), std::string::npos) << b << ": " << p.log();
  }
}

// The processes run with huge pages for their large heap blocks (common/memory.hpp): they
// re-execute themselves with glibc.malloc.hugetlb=1 in GLIBC_TUNABLES, unless OCC_HUGE_PAGES=0.
TEST(Conventions, ProcessesAskForHugePagesUnlessTurnedOff) {
  const fs::path dir = fresh_dir("hugepages");
  for (bool on : {true, false}) {
    if (!on) ::setenv("OCC_HUGE_PAGES", "0", 1);
    const fs::path port = dir / (on ? "on.port" : "off.port");
    Proc p({bin("switch_node"), "--id", "0", "--scene", "city:2x2:2:4:1", "--width", "32", "--height", "32",
            "--port-file", port.string(), "--timeout-ms", "20000"},
           dir / (on ? "on.log" : "off.log"));
    ::unsetenv("OCC_HUGE_PAGES");
    ASSERT_NE(wait_port(port, p), 0) << p.log();  // up and listening: past main's first line
    const std::string env = read_file("/proc/" + std::to_string(p.pid()) + "/environ");
    EXPECT_EQ(env.find("glibc.malloc.hugetlb=1") != std::string::npos, on) << (on ? "on" : "off");
    p.kill_now();
  }
}

// Scenes load on a thread of their own (common/memory.hpp in_own_arena), so the holes their freed
// CPU geometry leaves are not in the main thread's malloc arena: the value and any exception come
// back to the caller, and the work ran on another thread.
TEST(Conventions, InOwnArenaRunsOnAnotherThreadAndPassesResultsAndErrors) {
  const std::thread::id caller = std::this_thread::get_id();
  std::thread::id ran_on;
  auto v = occ::in_own_arena([&] {
    ran_on = std::this_thread::get_id();
    return std::make_unique<std::vector<int>>(1000, 7);
  });
  ASSERT_TRUE(v);
  EXPECT_EQ(v->size(), 1000u);
  EXPECT_EQ((*v)[999], 7);
  EXPECT_NE(ran_on, caller);
  EXPECT_THROW(occ::in_own_arena([]() -> int { throw std::runtime_error("scene file: bad header"); }), std::runtime_error);
}
