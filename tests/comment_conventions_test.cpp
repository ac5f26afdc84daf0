// Source comments state contracts and invariants: no comment cites an issue number, and none
// quotes a timing or a percentage that was measured. Figures and their history live in docs/ and
// in git. The test reads the repository's own source files (C++, GLSL, Python, shell, CMake) from
// OCC_SOURCE_DIR, takes their comments only (string literals, shell here-documents and code are
// skipped) and fails naming file:line for each comment line that breaks the rule:
//   - an issue number: the word issue or issues followed by a number, or # followed by a digit;
//   - a timing: a number followed by a unit of time (ms, us, µs, ns, s, sec, seconds, minutes), or
//     a percentage (a number followed by the percent sign or the word percent).
// A figure with a unit of time or a percentage is a contract, not a measurement, where it states a
// bound: one of the bound phrases in kBound (up to, at most, timeout, period, within, every,
// default, ...) within kBoundReach characters before or after it on the same comment line, or
// "after" right before it. Anything else (how long something took, how much faster it became) is
// a measurement and belongs in docs/. TheRuleTellsBoundsFromMeasurements lists examples of both.
// Unit test: reads files, starts no process.
#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

namespace fs = std::filesystem;

namespace {

// Files another change is rewriting; they are checked once it has landed. This list must become
// empty: remove each entry when its file is clean.
const std::vector<std::string> kNotYetChecked = {};

// Directories (relative to the source root, or any directory of these names) that hold no source
// of ours: build trees, run outputs, version control, shared data, third-party code, prose.
bool skipped_directory(const std::string& rel, const std::string& name) {
  if (name.empty() || name[0] == '.') return true;  // .git, .ci, editor state
  if (name.rfind("build", 0) == 0 || name.rfind("out", 0) == 0) return rel == name;  // top-level build*/, out*/
  if (rel == "shared") return true;  // scenes and tools beside a checkout, not ours
  if (name == "Testing" || name == "third_party" || name == "external" || name == "_deps") return true;
  return rel == "docs";
}

enum class Syntax { none, c, python, shell, cmake };

Syntax syntax_of(const fs::path& p) {
  const std::string ext = p.extension().string(), name = p.filename().string();
  if (ext == ".cpp" || ext == ".hpp" || ext == ".h" || ext == ".glsl") return Syntax::c;
  if (ext == ".py") return Syntax::python;
  if (ext == ".sh") return Syntax::shell;
  if (ext == ".cmake" || name == "CMakeLists.txt") return Syntax::cmake;
  return Syntax::none;
}

bool ident(char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_'; }

// Comment text by line number (1-based); a line with code and a comment holds the comment only.
using Comments = std::map<int, std::string>;

// C, C++ and GLSL: // and /* */ comments; "..." and '...' literals (escapes), raw strings
// R"d(...)d", and the digit separator of 1'000'000 are not comments.
Comments c_comments(const std::string& s) {
  Comments out;
  int line = 1;
  const size_t n = s.size();
  for (size_t i = 0; i < n; ++i) {
    const char c = s[i];
    if (c == '\n') {
      ++line;
    } else if (c == '/' && i + 1 < n && s[i + 1] == '/') {
      size_t e = s.find('\n', i);
      if (e == std::string::npos) e = n;
      out[line] += s.substr(i + 2, e - i - 2);
      i = e - 1;
    } else if (c == '/' && i + 1 < n && s[i + 1] == '*') {
      for (i += 2; i < n && !(s[i] == '*' && i + 1 < n && s[i + 1] == '/'); ++i) {
        if (s[i] == '\n') ++line;
        else out[line] += s[i];
      }
      ++i;  // past the '/'
    } else if (c == 'R' && i + 1 < n && s[i + 1] == '"' &&
               (i == 0 || !ident(s[i - 1]) || std::string("LuU8").find(s[i - 1]) != std::string::npos)) {
      const size_t open = s.find('(', i + 2);
      if (open == std::string::npos) break;
      const std::string end = ")" + s.substr(i + 2, open - i - 2) + "\"";
      size_t e = s.find(end, open);
      if (e == std::string::npos) e = n;
      line += static_cast<int>(std::count(s.begin() + static_cast<long>(i), s.begin() + static_cast<long>(e), '\n'));
      i = e + end.size() - 1;
    } else if (c == '"' || c == '\'') {
      if (c == '\'' && i > 0 && ident(s[i - 1])) {  // a digit separator, or a prefix such as L'x'
        size_t b = i;
        while (b > 0 && (ident(s[b - 1]) || s[b - 1] == '\'' || s[b - 1] == '.')) --b;
        if (std::isdigit(static_cast<unsigned char>(s[b]))) continue;
      }
      for (++i; i < n && s[i] != c && s[i] != '\n'; ++i)
        if (s[i] == '\\') ++i;
      if (i < n && s[i] == '\n') ++line;
    }
  }
  return out;
}

// Python: # comments outside '...', "...", '''...''' and """...""" strings (docstrings are
// strings: help text lives there).
Comments python_comments(const std::string& s) {
  Comments out;
  int line = 1;
  const size_t n = s.size();
  for (size_t i = 0; i < n; ++i) {
    const char c = s[i];
    if (c == '\n') {
      ++line;
    } else if (c == '#') {
      size_t e = s.find('\n', i);
      if (e == std::string::npos) e = n;
      out[line] += s.substr(i + 1, e - i - 1);
      i = e - 1;
    } else if (c == '"' || c == '\'') {
      const bool triple = i + 2 < n && s[i + 1] == c && s[i + 2] == c;
      const std::string close = triple ? std::string(3, c) : std::string(1, c);
      for (i += close.size(); i < n; ++i) {
        if (s[i] == '\\') {
          if (i + 1 < n && s[i + 1] == '\n') ++line;
          ++i;
        } else if (s.compare(i, close.size(), close) == 0) {
          i += close.size() - 1;
          break;
        } else if (s[i] == '\n') {
          ++line;
          if (!triple) break;
        }
      }
    }
  }
  return out;
}

// Shell: a # that begins a word outside quotes; '...' and "..." strings and here-documents
// (<<EOF ... EOF, <<-'EOF', ...) are not comments; neither are $#, ${#x} or ${x#y}.
Comments shell_comments(const std::string& s) {
  Comments out;
  int line = 1;
  const size_t n = s.size();
  std::vector<std::string> heredocs;  // delimiters whose bodies start at the next line
  for (size_t i = 0; i < n; ++i) {
    const char c = s[i];
    if (c == '\n') {
      ++line;
      for (const std::string& d : heredocs) {  // skip each body through its delimiter line
        while (i + 1 < n) {
          size_t e = s.find('\n', i + 1);
          if (e == std::string::npos) e = n;
          std::string body = s.substr(i + 1, e - i - 1);
          body.erase(0, body.find_first_not_of(" \t"));
          i = e;
          ++line;
          if (body == d) break;
        }
      }
      heredocs.clear();
    } else if (c == '\\') {
      if (i + 1 < n && s[i + 1] == '\n') ++line;
      ++i;
    } else if (c == '#' && (i == 0 || std::isspace(static_cast<unsigned char>(s[i - 1])) ||
                            std::string(";&|()").find(s[i - 1]) != std::string::npos)) {
      size_t e = s.find('\n', i);
      if (e == std::string::npos) e = n;
      out[line] += s.substr(i + 1, e - i - 1);
      i = e - 1;
    } else if (c == '\'') {
      for (++i; i < n && s[i] != '\''; ++i)
        if (s[i] == '\n') ++line;
    } else if (c == '"') {
      for (++i; i < n && s[i] != '"'; ++i) {
        if (s[i] == '\\') {
          if (i + 1 < n && s[i + 1] == '\n') ++line;
          ++i;
        } else if (s[i] == '\n') {
          ++line;
        }
      }
    } else if (c == '<' && i + 1 < n && s[i + 1] == '<' && (i + 2 >= n || s[i + 2] != '<')) {
      size_t k = i + 2;
      if (k < n && s[k] == '-') ++k;
      while (k < n && (s[k] == ' ' || s[k] == '\t')) ++k;
      const bool quoted = k < n && (s[k] == '\'' || s[k] == '"');
      if (quoted) ++k;
      size_t e = k;
      while (e < n && ident(s[e])) ++e;
      // a delimiter is a word that starts with a letter (<< 2 in $(( )) is a shift)
      if (e > k && !std::isdigit(static_cast<unsigned char>(s[k]))) {
        heredocs.push_back(s.substr(k, e - k));
        i = e - (quoted ? 0 : 1);
      }
    }
  }
  return out;
}

// CMake: # comments and #[[ ]] bracket comments outside "..." strings.
Comments cmake_comments(const std::string& s) {
  Comments out;
  int line = 1;
  const size_t n = s.size();
  for (size_t i = 0; i < n; ++i) {
    const char c = s[i];
    if (c == '\n') {
      ++line;
    } else if (c == '#' && i + 1 < n && s[i + 1] == '[' && s.find_first_not_of('=', i + 2) != std::string::npos &&
               s[s.find_first_not_of('=', i + 2)] == '[') {
      const size_t open = s.find_first_not_of('=', i + 2);
      const std::string close = "]" + std::string(open - i - 2, '=') + "]";
      size_t e = s.find(close, open);
      if (e == std::string::npos) e = n;
      for (size_t k = open + 1; k < e; ++k) {
        if (s[k] == '\n') ++line;
        else out[line] += s[k];
      }
      i = e + close.size() - 1;
    } else if (c == '#') {
      size_t e = s.find('\n', i);
      if (e == std::string::npos) e = n;
      out[line] += s.substr(i + 1, e - i - 1);
      i = e - 1;
    } else if (c == '"') {
      for (++i; i < n && s[i] != '"'; ++i) {
        if (s[i] == '\\') ++i;
        else if (s[i] == '\n') ++line;
      }
    }
  }
  return out;
}

const std::regex kIssue(R"((\bissues?\s*#?\s*\d)|((^|[^\w&])#\d))", std::regex::icase);
const std::regex kTiming(
    R"((^|[^\w])(\d+(\.\d+)?|\.\d+)(e[-+]?\d+)?\s*((ms|us|µs|ns|s|sec|secs|seconds?|milliseconds?|microseconds?|nanoseconds?|minutes?|min)\b|%|percent\b|per cent\b))",
    std::regex::icase);
// Phrases that make a figure a bound (a contract) rather than a measurement; see the top.
const std::regex kBound(
    R"(\b(up to|at most|at least|no more than|no longer than|timeouts?|time-?out|period|within|every|budget|limit|quota|deadline|wait(s|ing)?|default|retry|retries|polling)\b)",
    std::regex::icase);
const std::regex kAfter(R"(\bafter\s*$)", std::regex::icase);
constexpr size_t kBoundReach = 32;

// Each figure in `text` that is a timing or a percentage and states no bound.
bool measurement_in(const std::string& text) {
  for (auto it = std::sregex_iterator(text.begin(), text.end(), kTiming); it != std::sregex_iterator(); ++it) {
    const size_t at = static_cast<size_t>(it->position(2)), end = static_cast<size_t>(it->position() + it->length());
    const size_t from = at > kBoundReach ? at - kBoundReach : 0;
    const std::string before = text.substr(from, at - from), after = text.substr(end, kBoundReach);
    if (std::regex_search(before, kBound) || std::regex_search(after, kBound) || std::regex_search(before, kAfter))
      continue;
    return true;
  }
  return false;
}

std::string read_all(const fs::path& p) {
  std::ifstream f(p, std::ios::binary);
  std::ostringstream s;
  s << f.rdbuf();
  return s.str();
}

Comments comments_of(const fs::path& p, Syntax syntax) {
  const std::string s = read_all(p);
  switch (syntax) {
    case Syntax::c: return c_comments(s);
    case Syntax::python: return python_comments(s);
    case Syntax::shell: return shell_comments(s);
    case Syntax::cmake: return cmake_comments(s);
    case Syntax::none: break;
  }
  return {};
}

// Every source file under the root (relative paths, sorted), less the skipped directories.
std::vector<std::string> source_files(const fs::path& root) {
  std::vector<std::string> files;
  for (auto it = fs::recursive_directory_iterator(root); it != fs::recursive_directory_iterator(); ++it) {
    const std::string rel = fs::relative(it->path(), root).generic_string();
    if (it->is_directory()) {
      if (skipped_directory(rel, it->path().filename().string())) it.disable_recursion_pending();
    } else if (it->is_regular_file() && syntax_of(it->path()) != Syntax::none) {
      files.push_back(rel);
    }
  }
  std::sort(files.begin(), files.end());
  return files;
}

}  // namespace

TEST(SourceComments, TheScannerFindsCommentsOnly) {
  const Comments c = c_comments("int a = 1'000; // issue 3\nauto s = \"// 4 ms\"; /* 5 %\n x */ auto r = R\"x(// 6 s)x\";\n");
  ASSERT_EQ(c.size(), 3u);
  EXPECT_EQ(c.at(1), " issue 3");
  EXPECT_EQ(c.at(2), " 5 %");
  EXPECT_EQ(c.at(3), " x ");
  const Comments sh = shell_comments(
      "echo \"# 1 ms\" ${#x} $# ${y#*=}  # 2 ms\ncat <<EOF\n# 3 ms\nEOF\necho $((1 << 2)) # 4 ms\n");
  ASSERT_EQ(sh.size(), 2u);
  EXPECT_EQ(sh.at(1), " 2 ms");
  EXPECT_EQ(sh.at(5), " 4 ms");
  const Comments py = python_comments("x = '#1'  # a\n\"\"\"\n# b\n\"\"\"\ny = \"a\\\"#\"  # c\n");
  ASSERT_EQ(py.size(), 2u);
  EXPECT_EQ(py.at(1), " a");
  EXPECT_EQ(py.at(5), " c");
  const Comments cm = cmake_comments("set(A \"#x\") # one\n#[[ two\nthree ]] set(B 1)\n");
  ASSERT_EQ(cm.size(), 3u);
  EXPECT_EQ(cm.at(1), " one");
  EXPECT_EQ(cm.at(3), "three ");
}

TEST(SourceComments, TheRuleTellsBoundsFromMeasurements) {
  for (const char* bad : {"on llvmpipe this was 2.3 ms", "-15 % CPU", "took 31 s", "0.5ms a frame", "10-14% off",
                          "3 percent of samples", "the 1.5 s it lingers", "round to ~4e6 ms",
                          "spread over 0..4 ms"})
    EXPECT_TRUE(measurement_in(bad)) << bad;
  for (const char* ok : {"waits up to 30 s", "at most 2 ms of transmission", "retried every 50 ms", "a 2 ms period",
                         "a 5 s timeout", "60 s at most", "restarted after 2 s", "64-bit", "2 x 2 texels", "utf-8",
                         "0.5 scale", "1e-5 of the diagonal", "x % 4"})
    EXPECT_FALSE(measurement_in(ok)) << ok;
  for (const char* bad : {"issue 15", "Issue 17 item 4/5", "(#14)", "issues 7 and 8", "#3"})
    EXPECT_TRUE(std::regex_search(std::string(bad), kIssue)) << bad;
  for (const char* ok : {"#include", "the issue with this", "issued 3 queries", "a tissue 4", "&#39;"})
    EXPECT_FALSE(std::regex_search(std::string(ok), kIssue)) << ok;
}

TEST(SourceComments, CiteNoIssueNumbersOrTimings) {
  const fs::path root = OCC_SOURCE_DIR;
  const std::vector<std::string> files = source_files(root);
  ASSERT_GT(files.size(), 100u) << "too few source files under " << root;
  std::vector<std::string> found;
  for (const std::string& rel : files) {
    if (std::find(kNotYetChecked.begin(), kNotYetChecked.end(), rel) != kNotYetChecked.end()) continue;
    for (const auto& [line, text] : comments_of(root / rel, syntax_of(rel))) {
      if (std::regex_search(text, kIssue))
        found.push_back(rel + ":" + std::to_string(line) + ": an issue number:" + text);
      else if (measurement_in(text))
        found.push_back(rel + ":" + std::to_string(line) + ": a timing or percentage:" + text);
    }
  }
  std::string list;
  for (const std::string& f : found) list += "\n  " + f;
  EXPECT_TRUE(found.empty()) << found.size()
                             << " comment lines cite an issue number or a measured figure (say the contract; the "
                                "figures go in docs/):"
                             << list;
}
