// The cluster under a job launcher: scripts/cluster_rank.sh started as three ranks takes
// its role from the rank, the ranks meet through a rendezvous folder, and the frames equal the
// reference renderer's. Under `mpirun -np 3` (skipped without mpirun: Debian's openmpi-bin,
// scripts/setup.sh installs it) and, everywhere, as three processes given --rank by hand. A rank
// that fails stops the ranks waiting for it with its own error line; every wait is bounded.
#include <gtest/gtest.h>

#include <cstdlib>

#include "integration_util.hpp"

using namespace occtest;
using namespace std::chrono_literals;

namespace {

const std::string kScene = "city:3x3:2:5:1";
const std::vector<std::string> kView = {"--width", "96", "--height", "72"};

std::vector<std::string> rank_args(const fs::path& dir, const std::string& scene, std::vector<std::string> more) {
  std::vector<std::string> a = {std::string(OCC_SOURCE_DIR) + "/scripts/cluster_rank.sh",
                                "--rendezvous",
                                (dir / "rdv").string(),
                                "--scene",
                                scene,
                                "--out",
                                (dir / "cluster").string(),
                                "--address",
                                "127.0.0.1"};
  a.insert(a.end(), kView.begin(), kView.end());
  a.insert(a.end(), more.begin(), more.end());
  return a;
}

void expect_equals_reference(const fs::path& dir, const std::string& path, size_t frames) {
  const Outcome ref = run_reference(dir / "reference", kScene, path, kView);
  ASSERT_EQ(ref.code, 0) << ref.log;
  EXPECT_EQ(frame_count(dir / "cluster"), frames);
  const Outcome diff = frame_diff(dir / "reference", dir / "cluster");
  ASSERT_NE(diff_summary(diff.log).find("frames=" + std::to_string(frames)), std::string::npos) << differing_frames(diff.log);
  EXPECT_NE(diff_summary(diff.log).find(" differing_pixels=0 "), std::string::npos) << differing_frames(diff.log);
}

// The by-hand tests run as if no launcher had started them (a CI job under Slurm or mpirun has
// these set for the test itself).
void without_launcher() {
  for (const char* v : {"OMPI_COMM_WORLD_RANK", "OMPI_COMM_WORLD_SIZE", "OMPI_MCA_ess_base_jobid", "PMIX_RANK",
                        "PMIX_NAMESPACE", "PMI_RANK", "PMI_SIZE", "SLURM_PROCID", "SLURM_NTASKS", "SLURM_JOB_ID"})
    ::unsetenv(v);
}

std::string which(const std::string& program) {
  for (const char* d : {"/usr/bin/", "/usr/local/bin/", "/bin/"})
    if (fs::exists(d + program)) return d + program;
  return "";
}

}  // namespace

TEST(Launcher, MpirunStartsTheClusterAndFramesEqualTheReference) {
  const std::string mpirun = which("mpirun");
  if (mpirun.empty()) GTEST_SKIP() << "needs mpirun (Debian package openmpi-bin, scripts/setup.sh): not installed";
  const fs::path dir = fresh_dir("launcher_mpirun");
  ::setenv("OCC_BIN", OCC_BIN_DIR, 1);
  std::vector<std::string> a = {mpirun, "--allow-run-as-root", "--oversubscribe", "-np", "3"};
  const std::vector<std::string> ranks = rank_args(dir, kScene, {"--path", "walk:60"});
  a.insert(a.end(), ranks.begin(), ranks.end());
  const Outcome r = run_to_end(a, dir / "mpirun.log", 180s);
  ASSERT_EQ(r.code, 0) << r.log;
  EXPECT_NE(r.log.find("summary: frames=60 "), std::string::npos) << r.log;
  for (const char* role : {"0 (node0 on ", "1 (node1 on ", "2 (render_client on "})
    EXPECT_NE(r.log.find(std::string("cluster_rank ") + role), std::string::npos) << r.log;
  // The rendezvous is per job (the launcher's job id): one sub-folder with both addresses and the key.
  std::vector<fs::path> jobs;
  for (auto& e : fs::directory_iterator(dir / "rdv")) jobs.push_back(e.path());
  ASSERT_EQ(jobs.size(), 1u);
  EXPECT_EQ(read_file(jobs[0] / "node0.addr").rfind("127.0.0.1:", 0), 0u);
  EXPECT_EQ(read_file(jobs[0] / "node1.addr").rfind("127.0.0.1:", 0), 0u);
  EXPECT_EQ(fs::status(jobs[0] / "cluster.key").permissions() & fs::perms::group_read, fs::perms::none);
  EXPECT_NE(read_file(dir / "cluster" / "render_client.log").find("connected to switch node 0"), std::string::npos);
  expect_equals_reference(dir, "walk:60", 60);
}

// Without a launcher (--rank by hand, the rendezvous folder itself): the same cluster.
TEST(Launcher, RanksGivenByHandMeetThroughTheRendezvous) {
  const fs::path dir = fresh_dir("launcher_by_hand");
  ::setenv("OCC_BIN", OCC_BIN_DIR, 1);
  without_launcher();
  // The client first: it waits for both addresses.
  Proc client(rank_args(dir, kScene, {"--path", "walk:40", "--rank", "2"}), dir / "rank2.log");
  Proc node1(rank_args(dir, kScene, {"--path", "walk:40", "--rank", "1"}), dir / "rank1.log");
  Proc node0(rank_args(dir, kScene, {"--path", "walk:40", "--rank", "0"}), dir / "rank0.log");
  ASSERT_EQ(client.wait(180s), 0) << client.log() << node0.log() << node1.log();
  EXPECT_EQ(node0.wait(60s), 0) << node0.log();
  EXPECT_EQ(node1.wait(60s), 0) << node1.log();
  EXPECT_NE(client.log().find("summary: frames=40 "), std::string::npos) << client.log();
  EXPECT_TRUE(fs::exists(dir / "rdv" / "node0.addr"));
  expect_equals_reference(dir, "walk:40", 40);
}

// Node 0 cannot load its scene: it says why, and the ranks waiting for it stop at once with its
// line (not after --wait); a rank alone waits at most --wait seconds and says for what.
TEST(Launcher, AFailedRankStopsTheOthersWithItsOwnError) {
  const fs::path dir = fresh_dir("launcher_failed");
  ::setenv("OCC_BIN", OCC_BIN_DIR, 1);
  without_launcher();
  const std::string missing = (dir / "no_such_scene.gltf").string();
  Proc client(rank_args(dir, missing, {"--rank", "2", "--wait", "600"}), dir / "rank2.log");
  Proc node1(rank_args(dir, missing, {"--rank", "1", "--wait", "600"}), dir / "rank1.log");
  Proc node0(rank_args(dir, missing, {"--rank", "0", "--wait", "600"}), dir / "rank0.log");
  EXPECT_EQ(node0.wait(120s), 1) << node0.log();
  EXPECT_NE(node0.log().find("cluster_rank: node0 on "), std::string::npos) << node0.log();
  EXPECT_NE(node0.log().find(" exited before listening"), std::string::npos) << node0.log();
  for (Proc* p : {&node1, &client}) {
    EXPECT_EQ(p->wait(120s), 1) << p->log();
    EXPECT_NE(p->log().find(": node0 on "), std::string::npos) << p->log();
    EXPECT_NE(p->log().find("  error: " + missing + ": cannot open file"), std::string::npos) << p->log();
  }
  const fs::path alone = dir / "alone";
  fs::create_directories(alone);
  Proc waiting(rank_args(alone, kScene, {"--rank", "2", "--wait", "1"}), alone / "rank2.log");
  EXPECT_EQ(waiting.wait(60s), 1) << waiting.log();
  EXPECT_NE(waiting.log().find("node0 did not publish its address in " + (alone / "rdv").string() + " within 1 s"),
            std::string::npos)
      << waiting.log();
  Proc no_rank({std::string(OCC_SOURCE_DIR) + "/scripts/cluster_rank.sh", "--rendezvous", alone.string(), "--scene",
                kScene},
               alone / "no_rank.log");
  EXPECT_EQ(no_rank.wait(30s), 2) << no_rank.log();
  EXPECT_NE(no_rank.log().find("error: no rank: start it with mpirun -np 3 or srun -n 3"), std::string::npos)
      << no_rank.log();
}
