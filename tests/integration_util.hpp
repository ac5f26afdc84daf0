// Helpers for integration tests that start the real binaries: processes with logs, bounded
// waits, port files, reading logs and stats.csv.
#pragma once
#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
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

inline fs::path fresh_dir(const std::string& name) {
  fs::path d = fs::temp_directory_path() / ("occ_it_" + std::to_string(::getpid()) + "_" + name);
  fs::remove_all(d);
  fs::create_directories(d);
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
      ::setenv("LP_NUM_THREADS", "1", 0);
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

// stats.csv as column name -> values.
inline std::map<std::string, std::vector<double>> read_csv(const fs::path& file) {
  std::ifstream in(file);
  std::string line;
  std::vector<std::string> cols;
  std::map<std::string, std::vector<double>> out;
  if (std::getline(in, line)) {
    std::stringstream ss(line);
    for (std::string c; std::getline(ss, c, ',');) cols.push_back(c);
  }
  while (std::getline(in, line)) {
    std::stringstream ss(line);
    size_t i = 0;
    for (std::string c; std::getline(ss, c, ',') && i < cols.size(); ++i) out[cols[i]].push_back(std::stod(c));
  }
  return out;
}

inline double sum(const std::vector<double>& v) {
  double s = 0;
  for (double x : v) s += x;
  return s;
}

}  // namespace occtest
