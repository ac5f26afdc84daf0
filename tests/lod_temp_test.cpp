// Stale cache temporaries (cache_files.hpp: cache_temp_path, remove_stale_cache_temps) with real
// writer processes (lod_cache_writer, a host's start): one killed with SIGKILL while it writes its
// LOD cache, the next one (which removes that temporary) killed by the kernel mid-write (file size
// limit: SIGXFSZ, a partial regular file), then the next start removes that one too and writes a
// cache that loads; two writers
// that start together; and the rule for writers this process cannot ask (age).
#include <fcntl.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <thread>

#include <gtest/gtest.h>

#include "common/lod/lod_cache.hpp"
#include "common/scene/scene_io.hpp"

namespace fs = std::filesystem;
using namespace occ;

namespace {

// Big enough that its LOD cache (~100+ KB) does not fit in a pipe's buffer (64 KB).
const char* const kSpec = "hard:exit:24";

fs::path temp_dir(const std::string& name) {
  fs::path d = fs::temp_directory_path() / ("occ_lodtmp_" + std::to_string(::getpid()) + "_" + name);
  fs::remove_all(d);
  fs::create_directories(d / "cache");
  return d;
}

std::string file_text(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

std::vector<std::string> temporaries(const fs::path& dir) {
  std::vector<std::string> t;
  for (const auto& e : fs::directory_iterator(dir))
    if (e.path().filename().string().find(".tmp.") != std::string::npos) t.push_back(e.path().filename().string());
  return t;
}

// A writer process, started but held before exec until go() (so that its pid, and with it its
// temporary's name, is known before it writes). Its stdout and stderr go to DIR/<tag>.out/.err.
struct Writer {
  pid_t pid = -1;
  int go_fd = -1;
  fs::path out, err;

  Writer(const fs::path& dir, const std::string& tag, rlim_t file_size_limit = RLIM_INFINITY) {
    out = dir / (tag + ".out");
    err = dir / (tag + ".err");
    int fds[2];
    if (::pipe(fds) != 0) return;
    pid = ::fork();
    if (pid == 0) {
      ::close(fds[1]);
      char c;
      if (::read(fds[0], &c, 1) != 1) ::_exit(3);
      const int o = ::open(out.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
      const int e = ::open(err.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
      ::dup2(o, 1);
      ::dup2(e, 2);
      const rlimit none{0, 0}, fsize{file_size_limit, file_size_limit};
      ::setrlimit(RLIMIT_CORE, &none);
      ::setrlimit(RLIMIT_FSIZE, &fsize);
      const std::string bin = std::string(OCC_BIN_DIR) + "/lod_cache_writer";
      const std::string cache = (dir / "cache").string();
      ::execl(bin.c_str(), bin.c_str(), cache.c_str(), kSpec, static_cast<char*>(nullptr));
      ::_exit(127);
    }
    ::close(fds[0]);
    go_fd = fds[1];
  }
  void go() {
    ASSERT_EQ(::write(go_fd, "g", 1), 1);
    ::close(go_fd);
  }
  int wait() const {  // the wait status
    int status = 0;
    ::waitpid(pid, &status, 0);
    return status;
  }
};

TEST(LodCacheTemporaries, WritersKilledMidWriteLeaveTemporariesThatTheNextStartRemoves) {
  const fs::path dir = temp_dir("killed"), cache = dir / "cache";
  const std::string path = lod_cache_path(cache.string(), kSpec);

  // 1. SIGKILL while it writes: its temporary is a FIFO this test reads the first 4 KB of, so
  // the writer is blocked in the middle of writing the rest when the signal comes.
  Writer killed(dir, "killed");
  ASSERT_GT(killed.pid, 0);
  const std::string fifo = cache_temp_path(path, killed.pid);
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0644), 0);
  killed.go();
  const int fd = ::open(fifo.c_str(), O_RDONLY);  // returns once the writer opened its temporary
  ASSERT_GE(fd, 0);
  char buf[4096];
  size_t got = 0;
  for (ssize_t n; got < sizeof buf && (n = ::read(fd, buf + got, sizeof buf - got)) > 0;) got += size_t(n);
  ASSERT_EQ(got, sizeof buf) << "the writer wrote less than 4 KB: " << file_text(killed.err);
  EXPECT_EQ(std::string(buf, 8), std::string("OCCLOD\r\n", 8));
  ASSERT_EQ(::kill(killed.pid, SIGKILL), 0);
  const int s1 = killed.wait();
  ::close(fd);
  ASSERT_TRUE(WIFSIGNALED(s1) && WTERMSIG(s1) == SIGKILL) << s1;

  EXPECT_TRUE(fs::exists(fifo));
  EXPECT_FALSE(fs::exists(path));

  // 2. The next start removes that temporary; it is killed by the kernel at a file size limit
  // while it writes its own: a partial regular file.
  Writer cut(dir, "cut", 8192);
  cut.go();
  const int s2 = cut.wait();
  ASSERT_TRUE(WIFSIGNALED(s2) && WTERMSIG(s2) == SIGXFSZ) << s2 << ": " << file_text(cut.err);
  EXPECT_NE(file_text(cut.err).find("removed 1 temporary cache file(s) of writers that are gone"), std::string::npos)
      << file_text(cut.err);
  EXPECT_FALSE(fs::exists(fifo));
  const std::string partial = cache_temp_path(path, cut.pid);
  ASSERT_TRUE(fs::is_regular_file(partial));
  EXPECT_EQ(fs::file_size(partial), 8192u);
  EXPECT_EQ(temporaries(cache), std::vector<std::string>{fs::path(partial).filename().string()});
  EXPECT_FALSE(fs::exists(path));

  // 3. The start after that removes it too, builds and writes a cache that loads.
  Writer next(dir, "next");
  next.go();
  const int s3 = next.wait();
  ASSERT_TRUE(WIFEXITED(s3) && WEXITSTATUS(s3) == 0) << file_text(next.err);
  EXPECT_NE(file_text(next.err).find("removed 1 temporary cache file(s) of writers that are gone"), std::string::npos)
      << file_text(next.err);
  EXPECT_TRUE(temporaries(cache).empty());
  Scene scene = load_scene(kSpec);
  const Hierarchy h = Hierarchy::build(scene, {});
  std::string why;
  const auto lod = LodData::load(path, LodData::cache_key(h, {}), scene, h, &why);
  ASSERT_TRUE(lod.has_value()) << why;
  EXPECT_GT(fs::file_size(path), 68u << 10) << "the first writer was blocked mid-write: more than the 4 KB read "
                                                "and a pipe's 64 KB";
  char hash[17];
  std::snprintf(hash, sizeof hash, "%016llx", static_cast<unsigned long long>(lod->hash()));
  EXPECT_EQ(file_text(next.out), std::string(hash) + "\n");
  fs::remove_all(dir);
}

// Cluster processes start together: one builds and writes (the other waits on the build lock,
// cache_files.hpp, then reads what was written); no temporary is left, both agree on the data.
TEST(LodCacheTemporaries, WritersThatStartTogetherBuildTheSameCache) {
  const fs::path dir = temp_dir("together"), cache = dir / "cache";
  Writer a(dir, "a"), b(dir, "b");
  a.go();
  b.go();
  const int sa = a.wait(), sb = b.wait();
  ASSERT_TRUE(WIFEXITED(sa) && WEXITSTATUS(sa) == 0) << file_text(a.err);
  ASSERT_TRUE(WIFEXITED(sb) && WEXITSTATUS(sb) == 0) << file_text(b.err);
  EXPECT_EQ(file_text(a.out), file_text(b.out));
  EXPECT_EQ(file_text(a.out).size(), 17u);
  EXPECT_EQ(file_text(a.err).find("removed"), std::string::npos) << file_text(a.err);
  EXPECT_EQ(file_text(b.err).find("removed"), std::string::npos) << file_text(b.err);
  EXPECT_TRUE(temporaries(cache).empty());
  Writer c(dir, "c");  // the next start loads what they wrote
  c.go();
  ASSERT_EQ(c.wait(), 0) << file_text(c.err);
  EXPECT_EQ(file_text(c.out), file_text(a.out));
  EXPECT_NE(file_text(c.err).find("loaded in"), std::string::npos) << file_text(c.err);
  fs::remove_all(dir);
}

TEST(LodCacheTemporaries, WhoseWriterIsGone) {
  const fs::path dir = temp_dir("rules") / "cache";
  const std::string base = (dir / "s-00000000.lod").string();
  pid_t dead = ::fork();
  if (dead == 0) ::_exit(0);
  ::waitpid(dead, nullptr, 0);  // reaped: no such process now
  auto touch = [&](const std::string& name, int hours_ago) {
    const fs::path p = dir / name;
    std::ofstream(p) << "partial";
    fs::last_write_time(p, fs::file_time_type::clock::now() - std::chrono::hours(hours_ago));
  };
  const std::string live = fs::path(cache_temp_path(base)).filename().string();  // this process
  const std::string gone = fs::path(cache_temp_path(base, dead)).filename().string();
  touch(live, 0);
  touch(gone, 0);
  const std::string reused = fs::path(cache_temp_path(base, 1)).filename().string();  // pid 1 runs: not its writer
  touch(reused, 2);
  touch("s-00000000.scene.tmp.otherhost.4026531836.77", 2);  // another host, untouched for 2 h
  touch("s-00000000.lod.tmp.otherhost.4026531836.78", 0);    // another host, being written
  touch("s-00000000.lod.tmp.1234", 2);                       // an older name, untouched for 2 h
  touch("notes.txt.tmp.otherhost.1.2", 2);                   // not a cache file's temporary
  touch("s-00000000.lod", 2);                                // a cache
  EXPECT_EQ(remove_stale_cache_temps(dir.string()), 4u);
  std::vector<std::string> left;
  for (const auto& e : fs::directory_iterator(dir)) left.push_back(e.path().filename().string());
  std::sort(left.begin(), left.end());
  std::vector<std::string> expected = {live, "notes.txt.tmp.otherhost.1.2", "s-00000000.lod",
                                       "s-00000000.lod.tmp.otherhost.4026531836.78"};
  std::sort(expected.begin(), expected.end());
  EXPECT_EQ(left, expected);
  EXPECT_EQ(remove_stale_cache_temps((dir / "none").string()), 0u);
  fs::remove_all(dir.parent_path());
}

}  // namespace

// Processes that find a cache missing at the same time build it once: the one that holds the
// build lock builds, the others wait for it (saying so) and then read what it wrote. Two holders in
// one process conflict as two processes do (an flock per open file): the second gets the lock only
// after the first let it go, whatever the threads' timing.
TEST(CacheBuildLock, ASecondBuilderWaitsUntilTheFirstIsDone) {
  const fs::path dir = temp_dir("build_lock");
  const std::string path = (dir / "x.lod").string();
  std::atomic<bool> first_done{false}, second_saw_done{false}, second_in{false};
  auto first = std::make_unique<CacheBuildLock>(path, "first");
  testing::internal::CaptureStderr();
  std::thread second([&] {
    CacheBuildLock lock(path, "second");
    second_saw_done = first_done.load();
    second_in = true;
  });
  for (int i = 0; i < 200 && !second_in; ++i) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  EXPECT_FALSE(second_in.load());
  first_done = true;
  first.reset();
  second.join();
  EXPECT_TRUE(second_saw_done.load());
  const std::string err = testing::internal::GetCapturedStderr();
  EXPECT_NE(err.find("second: waiting for another process that builds " + path), std::string::npos) << err;
  CacheBuildLock again(path, "third");  // free again
}
