#include "common/cli.hpp"

#include <cmath>
#include <iostream>
#include <sstream>
#include <stdexcept>

#include "common/error.hpp"

namespace occ {

namespace {
// `v` as a whole number min..max, else InputError naming --name (`other`: what else it may be).
long whole_number(const std::string& name, const std::string& v, long min, long max, const std::string& other = "") {
  size_t used = 0;
  long n = 0;
  try {
    n = std::stol(v, &used);
  } catch (...) {
    used = 0;
  }
  if (used == 0 || used != v.size()) throw InputError("--" + name + " '" + v + "': not a whole number" + other);
  if (n < min || n > max)
    throw InputError("--" + name + " '" + v + "': must be " + std::to_string(min) + ".." + std::to_string(max) + other);
  return n;
}
}  // namespace

Cli::Cli(std::string program, std::string usage, std::string description)
    : program_(std::move(program)), usage_(std::move(usage)), description_(std::move(description)) {}

void Cli::add(Opt o) {
  for (const Opt& other : opts_)
    if (other.name == o.name) throw std::logic_error("--" + o.name + " declared twice");
  o.group = group_;
  opts_.push_back(std::move(o));
}

void Cli::flag(const std::string& name, bool* out, const std::string& help) {
  add({name, "", help, false, [out](const std::string&) { *out = true; }, ""});
}

void Cli::option(const std::string& name, std::string* out, const std::string& value, const std::string& help) {
  add({name, value, help, true, [out](const std::string& v) { *out = v; }, *out});
}

void Cli::option(const std::string& name, int* out, long min, long max, const std::string& help) {
  integer(name, out, min, max, help);
}

void Cli::option(const std::string& name, uint32_t* out, long min, long max, const std::string& help) {
  integer(name, out, min, max, help);
}

void Cli::option(const std::string& name, std::optional<int>* out, long min, long max, const std::string& help) {
  add({name, "N|auto", help, true,
                   [=](const std::string& v) {
                     if (v == "auto")
                       *out = std::nullopt;
                     else
                       *out = int(whole_number(name, v, min, max, " or auto"));
                   },
                   *out ? std::to_string(**out) : "auto"});
}

template <class T>
void Cli::integer(const std::string& name, T* out, long min, long max, const std::string& help) {
  add({name, "N", help, true, [=](const std::string& v) { *out = T(whole_number(name, v, min, max)); },
                   std::to_string(*out)});
}

void Cli::option(const std::string& name, double* out, double min, double max, const std::string& help) {
  std::ostringstream def;
  def << *out;
  add({name, "X", help, true,
                   [=](const std::string& v) {
                     const std::optional<double> parsed = parse_finite(v);
                     if (!parsed) throw InputError("--" + name + " '" + v + "': not a finite number");
                     const double x = *parsed;
                     if (x < min || x > max) {
                       std::ostringstream r;
                       r << "--" << name << " '" << v << "': must be in [" << min << ", " << max << "]";
                       throw InputError(r.str());
                     }
                     *out = x;
                   },
                   def.str()});
}

std::optional<double> parse_finite(const std::string& text) {
  size_t used = 0;
  double v = NAN;
  try {
    v = std::stod(text, &used);
  } catch (...) {
    used = 0;
  }
  if (used == 0 || used != text.size() || !std::isfinite(v)) return std::nullopt;
  return v;
}

void Cli::word_option(const std::string& name, const std::vector<std::string>& words, const std::string& default_word,
                      const std::string& help, std::function<void(size_t)> set) {
  std::string alts;
  for (auto& w : words) alts += (alts.empty() ? "" : "|") + w;
  add({name, alts, help, true,
                   [=](const std::string& v) {
                     for (size_t i = 0; i < words.size(); ++i)
                       if (v == words[i]) return set(i);
                     throw InputError("--" + name + " '" + v + "': expected one of " + alts);
                   },
                   default_word});
}

void Cli::choice(const std::string& name, std::string* out, std::vector<std::string> words, const std::string& help) {
  word_option(name, words, *out, help, [out, words](size_t i) { *out = words[i]; });
}

void Cli::custom(const std::string& name, const std::string& value, const std::string& default_text,
                 const std::string& help, std::function<void(const std::string&)> set) {
  add({name, value, help, true, std::move(set), default_text});
}

long Cli::whole(const std::string& name, const std::string& v, long min, long max, const std::string& other) {
  return whole_number(name, v, min, max, other);
}

void Cli::on_off(const std::string& name, bool* out, const std::string& help) {
  choice<bool>(name, out, {{"on", true}, {"off", false}}, help);
}

void Cli::multi(const std::string& name, std::vector<std::string>* out, const std::string& value,
                const std::string& help) {
  add({name, value, help, true, [out](const std::string& v) { out->push_back(v); }, ""});
}

bool Cli::parse(int argc, char** argv) {
  for (int i = 1; i < argc; ++i) {
    std::string a = argv[i];
    if (a == "--help" || a == "-h") {
      std::cout << help();
      return false;
    }
    if (a == "--version") {
      std::cout << program_ << " (occswitch) " << version_text() << "\n";
      return false;
    }
    if (a.rfind("--", 0) != 0) throw InputError("unexpected argument '" + a + "' (see " + program_ + " --help)");
    std::string name = a.substr(2), value;
    bool inline_value = false;
    if (auto eq = name.find('='); eq != std::string::npos) {
      value = name.substr(eq + 1);
      name = name.substr(0, eq);
      inline_value = true;
    }
    const Opt* opt = nullptr;
    for (const Opt& o : opts_)
      if (o.name == name) opt = &o;
    if (!opt) throw InputError("unknown flag --" + name + " (see " + program_ + " --help)");
    if (opt->takes_value && !inline_value) {
      if (i + 1 >= argc) throw InputError("--" + name + " needs a value (" + opt->value + ")");
      value = argv[++i];
    } else if (!opt->takes_value && inline_value) {
      throw InputError("--" + name + " takes no value");
    }
    opt->set(value);
  }
  return true;
}

std::string Cli::help() const {
  std::ostringstream o;
  o << "usage: " << program_ << " " << usage_ << "\n\n" << description_ << "\n";
  static const char* const kHeadings[] = {"scene and path", "output", "cluster and network", "accuracy", "expert"};
  for (int g = 0; g <= int(CliGroup::expert); ++g) {
    bool heading = false;
    for (const Opt& opt : opts_) {
      if (int(opt.group) != g) continue;
      if (!heading) o << "\n" << kHeadings[g] << ":\n";
      heading = true;
      std::string left = "  --" + opt.name + (opt.takes_value ? " " + opt.value : "");
      o << left << std::string(left.size() < 30 ? 30 - left.size() : 1, ' ') << opt.help;
      if (opt.takes_value && !opt.default_text.empty()) o << " (default " << opt.default_text << ")";
      o << "\n";
    }
  }
  o << "\n  --help                      this text\n";
  o << "  --version                   the occswitch version\n";
  return o.str();
}

std::string version_text() {
#ifndef OCC_VERSION
#define OCC_VERSION "unknown"
#endif
#ifndef OCC_GIT
#define OCC_GIT ""
#endif
  const std::string git = OCC_GIT;
  return std::string(OCC_VERSION) + (git.empty() ? "" : " (git " + git + ")");
}

int run_main(const std::function<int()>& body) {
  try {
    return body();
  } catch (const InputError& e) {
    std::cerr << "error: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "error: " << e.what() << "\n";
    return 1;
  }
}

}  // namespace occ
