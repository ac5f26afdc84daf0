// A small command-line parser shared by every binary: --help text generated from the
// declarations, every value checked (range, number syntax), unknown flags rejected. Errors throw
// InputError ("--width '0': must be 16..16384"); run_main() turns them into one "error:" line.
#pragma once
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace occ {

// The headings --help sorts options under, printed in this order.
enum class CliGroup { scene, output, cluster, accuracy, expert };

class Cli {
 public:
  Cli(std::string program, std::string usage, std::string description);

  // The options declared from now on are listed under `g`'s heading (before any call: expert).
  void group(CliGroup g) { group_ = g; }
  // How many options are declared (--help and --version not counted).
  size_t count() const { return opts_.size(); }

  void flag(const std::string& name, bool* out, const std::string& help);
  void option(const std::string& name, std::string* out, const std::string& value, const std::string& help);
  void option(const std::string& name, int* out, long min, long max, const std::string& help);
  void option(const std::string& name, uint32_t* out, long min, long max, const std::string& help);
  void option(const std::string& name, double* out, double min, double max, const std::string& help);
  // A whole number min..max, or the word auto (nullopt: the program decides).
  void option(const std::string& name, std::optional<int>* out, long min, long max, const std::string& help);
  // One of a fixed set of words.
  void choice(const std::string& name, std::string* out, std::vector<std::string> words, const std::string& help);
  // One of a fixed set of words, each naming a value of T (an enum): typed configuration.
  template <class T>
  void choice(const std::string& name, T* out, std::vector<std::pair<std::string, T>> words, const std::string& help);
  // An option whose word `set` parses (throwing InputError naming --name for a bad one);
  // `value` names its words in --help, `default_text` the default.
  void custom(const std::string& name, const std::string& value, const std::string& default_text,
              const std::string& help, std::function<void(const std::string&)> set);
  // "on" | "off" into a bool.
  void on_off(const std::string& name, bool* out, const std::string& help);
  // Repeatable option: each occurrence appends.
  void multi(const std::string& name, std::vector<std::string>* out, const std::string& value, const std::string& help);

  // `v` as a whole number min..max, else InputError "--name 'v': ..." (`other`: what else it may be).
  static long whole(const std::string& name, const std::string& v, long min, long max, const std::string& other = "");

  // Returns false when --help or --version was given (printed to stdout): the caller exits 0.
  bool parse(int argc, char** argv);
  std::string help() const;

 private:
  struct Opt {
    std::string name, value, help;
    bool takes_value;
    std::function<void(const std::string&)> set;
    std::string default_text;
    CliGroup group = CliGroup::expert;
  };
  void add(Opt o);
  // Registers a --name WORD option: set(word) is called for words in `words`, others are refused.
  void word_option(const std::string& name, const std::vector<std::string>& words, const std::string& default_word,
                   const std::string& help, std::function<void(size_t)> set);
  template <class T>
  void integer(const std::string& name, T* out, long min, long max, const std::string& help);
  std::string program_, usage_, description_;
  std::vector<Opt> opts_;
  CliGroup group_ = CliGroup::expert;
};

template <class T>
void Cli::choice(const std::string& name, T* out, std::vector<std::pair<std::string, T>> words,
                 const std::string& help) {
  std::vector<std::string> names;
  std::string def;
  for (auto& [w, v] : words) {
    names.push_back(w);
    if (v == *out) def = w;
  }
  word_option(name, names, def, help, [out, words](size_t i) { *out = words[i].second; });
}

// "0.1.0 (git 1a2b3c4)": the VERSION file and the commit the build was configured at. --version
// prints "PROGRAM (occswitch) 0.1.0 (git 1a2b3c4)".
std::string version_text();

// Runs body(); InputError -> "error: <what>" exit 2, other exceptions -> "error: <what>" exit 1.
int run_main(const std::function<int()>& body);

// The whole of `text` as a finite number (std::stod syntax: leading white space allowed, nothing
// after the number); nullopt for anything else (empty, junk after it, out of range, inf, nan).
std::optional<double> parse_finite(const std::string& text);

}  // namespace occ
