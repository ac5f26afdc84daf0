// Helpers for integration tests that start the real binaries: processes with logs, bounded
// waits, port files, reading logs and stats.csv, the "one clear error line" check, the reference
// renderer and frame_diff. The three-process cluster is in cluster_run.hpp.
#pragma once
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

namespace occtest {

namespace fs = std::filesystem;

inline std::string bin(const std::string& name) { return std::string(OCC_BIN_DIR) + "/" + name; }
inline bool have_shared() { return fs::exists(std::string(OCC_SHARED_DIR) + "/scenes"); }
inline std::string shared(const std::string& rel) { return std::string(OCC_SHARED_DIR) + "/" + rel; }

// The folders fresh_dir made. They are removed when the test program ends if every test in it
// passed (and OCC_KEEP_TEST_DIRS is unset); a failure keeps them, with their logs, and says where.
// (Constructed at the first fresh_dir, inside a test, so destroyed before GoogleTest's UnitTest.)
class TestDirs {
 public:
  static TestDirs& get() {
    static TestDirs dirs;
    return dirs;
  }
  void add(const fs::path& d) { dirs_.push_back(d); }
  ~TestDirs() {
    const bool failed = ::testing::UnitTest::GetInstance()->Failed();
    const char* keep = std::getenv("OCC_KEEP_TEST_DIRS");
    for (const auto& d : dirs_) {
      if (failed || (keep && *keep && std::string(keep) != "0")) {
        std::fprintf(stderr, "kept %s\n", d.c_str());
      } else {
        std::error_code ec;
        fs::remove_all(d, ec);
      }
    }
  }

 private:
  std::vector<fs::path> dirs_;
};

inline fs::path fresh_dir(const std::string& name) {
  fs::path d = fs::temp_directory_path() / ("occ_it_" + std::to_string(::getpid()) + "_" + name);
  fs::remove_all(d);
  fs::create_directories(d);
  TestDirs::get().add(d);
  return d;
}

inline std::string read_file(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// A child process with stdout+stderr in a log file. Killed on destruction if still running.
class Proc {
 public:
  Proc(std::vector<std::string> argv, const fs::path& log) : log_(log) {
    pid_ = ::fork();
    if (pid_ == 0) {
      int fd = ::open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
      ::dup2(fd, 1);
      ::dup2(fd, 2);
      std::vector<char*> args;
      for (auto& a : argv) args.push_back(a.data());
      args.push_back(nullptr);
      ::setenv("LP_NUM_THREADS", "0", 0);  // as scripts/test.sh: no rasteriser threads (docs/hard_cases.md)
      ::execv(args[0], args.data());
      ::_exit(127);
    }
  }
  ~Proc() {
    if (running()) {
      ::kill(pid_, SIGKILL);
      ::waitpid(pid_, nullptr, 0);
    }
  }
  bool running() {
    if (done_) return false;
    int st = 0;
    if (::waitpid(pid_, &st, WNOHANG) == pid_) {
      done_ = true;
      code_ = WIFEXITED(st) ? WEXITSTATUS(st) : 128 + WTERMSIG(st);
    }
    return !done_;
  }
  // Exit code, or -1 if still running after timeout (then it is killed).
  int wait(std::chrono::milliseconds timeout) {
    auto end = std::chrono::steady_clock::now() + timeout;
    while (running() && std::chrono::steady_clock::now() < end) std::this_thread::sleep_for(std::chrono::milliseconds(20));
    if (running()) {
      ::kill(pid_, SIGKILL);
      ::waitpid(pid_, nullptr, 0);
      done_ = true;
      return -1;
    }
    return code_;
  }
  void kill_now() { ::kill(pid_, SIGKILL); }
  void signal(int sig) { ::kill(pid_, sig); }
  pid_t pid() const { return pid_; }
  std::string log() const { return read_file(log_); }

 private:
  fs::path log_;
  pid_t pid_ = -1;
  bool done_ = false;
  int code_ = -1;
};

// Waits for a port file and returns its port (0 on timeout).
inline int wait_port(const fs::path& file, Proc& owner, std::chrono::milliseconds timeout = std::chrono::seconds(60)) {
  auto end = std::chrono::steady_clock::now() + timeout;
  while (std::chrono::steady_clock::now() < end && owner.running()) {
    std::string s = read_file(file);
    if (!s.empty() && s.back() == '\n') return std::stoi(s);
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  return 0;
}

// Every cell of a CSV file with a header line, row by row: cell(column name, text). Cells past
// the header's columns are passed over.
template <class Cell>
void for_each_csv_cell(const fs::path& file, Cell cell) {
  std::ifstream in(file);
  std::string line;
  std::vector<std::string> cols;
  if (std::getline(in, line)) {
    std::stringstream ss(line);
    for (std::string c; std::getline(ss, c, ',');) cols.push_back(c);
  }
  while (std::getline(in, line)) {
    std::stringstream ss(line);
    size_t i = 0;
    for (std::string c; std::getline(ss, c, ',') && i < cols.size(); ++i) cell(cols[i], c);
  }
}

// stats.csv as column name -> values.
inline std::map<std::string, std::vector<double>> read_csv(const fs::path& file) {
  std::map<std::string, std::vector<double>> out;
  for_each_csv_cell(file, [&](const std::string& col, const std::string& c) {
    char* end = nullptr;
    const double v = std::strtod(c.c_str(), &end);
    if (end != c.c_str() && *end == '\0') out[col].push_back(v);  // text columns (mode): read_csv_text
  });
  return out;
}

// The text columns of stats.csv (e.g. the cluster's mode) as column name -> values.
inline std::map<std::string, std::vector<std::string>> read_csv_text(const fs::path& file) {
  std::map<std::string, std::vector<std::string>> out;
  for_each_csv_cell(file, [&](const std::string& col, const std::string& c) { out[col].push_back(c); });
  return out;
}

inline double sum(const std::vector<double>& v) {
  double s = 0;
  for (double x : v) s += x;
  return s;
}

// Waits until stats.csv has at least `frames` rows (for at most `timeout`, and no longer than
// `writer` runs when given); returns how many rows it has.
inline size_t wait_frames(const fs::path& stats, size_t frames, std::chrono::milliseconds timeout,
                          Proc* writer = nullptr) {
  const auto end = std::chrono::steady_clock::now() + timeout;
  size_t n = read_csv(stats)["frame"].size();
  while (n < frames && std::chrono::steady_clock::now() < end && (!writer || writer->running())) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    n = read_csv(stats)["frame"].size();
  }
  return n;
}

// How a process ended: its exit code (-1: still running at the timeout, then killed) and its log.
struct Outcome {
  int code = -1;
  std::string log;
};

inline Outcome run_to_end(std::vector<std::string> argv, const fs::path& log, std::chrono::milliseconds timeout) {
  Proc p(std::move(argv), log);
  const int code = p.wait(timeout);
  return {code, p.log()};
}

struct OneError {
  int code = 0;            // the exit code it must have (0: any failure, 1..127)
  bool whole_log = false;  // and the error line is all the process printed
};

// Bad input gets one clear error: the process failed without crashing (exit 1..127), exactly one
// line of its log starts with "error:", and that line contains every fragment.
inline void expect_one_error(const Outcome& o, std::initializer_list<std::string> fragments, OneError how = {}) {
  EXPECT_GT(o.code, 0) << o.log;
  EXPECT_LT(o.code, 128) << "crashed: " << o.log;
  if (how.code != 0) {
    EXPECT_EQ(o.code, how.code) << o.log;
  }
  size_t errors = 0;
  std::string line;
  std::istringstream in(o.log);
  for (std::string l; std::getline(in, l);)
    if (l.rfind("error:", 0) == 0) {
      ++errors;
      line = l;
    }
  EXPECT_EQ(errors, 1u) << o.log;
  for (const auto& f : fragments) EXPECT_NE(line.find(f), std::string::npos) << "missing '" << f << "' in: " << line;
  if (how.whole_log) {
    EXPECT_EQ(o.log.rfind("error: ", 0), 0u) << o.log;
    EXPECT_EQ(std::count(o.log.begin(), o.log.end(), '\n'), 1) << o.log;
  }
}

// The reference renderer (render_client --reference, one process) drawing `path` into `out`, with
// more flags (viewport, --cull ...); its log is out/reference.log.
inline Outcome run_reference(const fs::path& out, const std::string& scene, const std::string& path,
                             const std::vector<std::string>& flags,
                             std::chrono::milliseconds timeout = std::chrono::seconds(300)) {
  fs::create_directories(out);
  std::vector<std::string> a = {bin("render_client"), "--scene", scene, "--path", path, "--out",
                                out.string()};
  a.insert(a.end(), flags.begin(), flags.end());
  return run_to_end(a, out / "reference.log", timeout);
}

// frame_diff A B FLAGS: exit 0 when every frame is within the budget the flags set (by default
// --max-fraction 0.0001, as in the cluster tests); its log is kept beside A.
inline Outcome frame_diff(const fs::path& a, const fs::path& b,
                          const std::vector<std::string>& flags = {"--max-fraction", "0.0001"}) {
  static int n = 0;
  std::vector<std::string> args = {bin("frame_diff"), a.string(), b.string()};
  args.insert(args.end(), flags.begin(), flags.end());
  const fs::path log = a.parent_path() / ("diff_" + a.filename().string() + "_" + b.filename().string() + "_" +
                                          std::to_string(n++) + ".log");
  return run_to_end(args, log, std::chrono::seconds(120));
}

// frame_diff's last summary ("frames=N differing_pixels=..."), or its whole log if it has none.
inline std::string diff_summary(const std::string& log) {
  const size_t last = log.rfind("frames=");
  return last == std::string::npos ? log : log.substr(last);
}

// frame_diff's log without the frames that equal (a failure shows the frames that differ and the
// summary, not thousands of lines a CI log cuts).
inline std::string differing_frames(const std::string& log) {
  std::string out, line;
  for (std::istringstream in(log); std::getline(in, line);)
    if (line.find(": 0 differing pixels") == std::string::npos) out += line + "\n";
  return out;
}

// The frame_NNNNN.png files in a directory.
inline size_t frame_count(const fs::path& dir) {
  size_t n = 0;
  for (auto& e : fs::directory_iterator(dir)) {
    const std::string f = e.path().filename().string();
    n += f.rfind("frame_", 0) == 0 && f.size() > 4 && f.substr(f.size() - 4) == ".png";
  }
  return n;
}

}  // namespace occtest
