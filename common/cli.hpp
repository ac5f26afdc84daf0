// A small command-line parser shared by every binary: --help text generated from the
// declarations, every value checked (range, number syntax), unknown flags rejected. Errors throw
// InputError ("--width '0': must be 16..16384"); run_main() turns them into one "error:" line.
#pragma once
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace occ {

class Cli {
 public:
  Cli(std::string program, std::string usage, std::string description);

  void flag(const std::string& name, bool* out, const std::string& help);
  void option(const std::string& name, std::string* out, const std::string& value, const std::string& help);
  void option(const std::string& name, int* out, long min, long max, const std::string& help);
  void option(const std::string& name, uint32_t* out, long min, long max, const std::string& help);
  void option(const std::string& name, double* out, double min, double max, const std::string& help);
  // One of a fixed set of words.
  void choice(const std::string& name, std::string* out, std::vector<std::string> words, const std::string& help);
  // Repeatable option: each occurrence appends.
  void multi(const std::string& name, std::vector<std::string>* out, const std::string& value, const std::string& help);

  // Returns false when --help was given (help printed to stdout): the caller exits 0.
  bool parse(int argc, char** argv);
  std::string help() const;

 private:
  struct Opt {
    std::string name, value, help;
    bool takes_value;
    std::function<void(const std::string&)> set;
    std::string default_text;
  };
  template <class T>
  void integer(const std::string& name, T* out, long min, long max, const std::string& help);
  std::string program_, usage_, description_;
  std::vector<Opt> opts_;
};

// Runs body(); InputError -> "error: <what>" exit 2, other exceptions -> "error: <what>" exit 1.
int run_main(const std::function<int()>& body);

// The whole of `text` as a finite number (std::stod syntax: leading white space allowed, nothing
// after the number); nullopt for anything else (empty, junk after it, out of range, inf, nan).
std::optional<double> parse_finite(const std::string& text);

}  // namespace occ
