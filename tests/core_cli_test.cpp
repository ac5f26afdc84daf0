#include <gtest/gtest.h>

#include "common/cli.hpp"
#include "common/error.hpp"

using namespace occ;

namespace {
struct Args {
  std::vector<std::string> s;
  std::vector<char*> v;
  Args(std::initializer_list<const char*> a) : s(a.begin(), a.end()) {
    for (auto& x : s) v.push_back(x.data());
  }
  int argc() { return int(v.size()); }
  char** argv() { return v.data(); }
};

std::string error_of(Cli& cli, Args a) {
  try {
    cli.parse(a.argc(), a.argv());
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}
}  // namespace

TEST(Cli, ParsesEveryKindAndRejectsBadValuesByName) {
  int width = 64;
  double tau = 0;
  bool ref = false;
  std::string mode = "lockstep", out;
  Cli cli("prog", "[options]", "test");
  cli.option("width", &width, 16, 16384, "w");
  cli.option("pixel-error", &tau, 0, 1000, "tau");
  cli.flag("reference", &ref, "r");
  cli.choice("camera-mode", &mode, {"latest", "lockstep"}, "m");
  cli.option("out", &out, "DIR", "o");
  Args ok{"prog", "--width", "320", "--pixel-error=2.5", "--reference", "--camera-mode", "latest", "--out", "x"};
  ASSERT_TRUE(cli.parse(ok.argc(), ok.argv()));
  EXPECT_EQ(width, 320);
  EXPECT_EQ(tau, 2.5);
  EXPECT_TRUE(ref);
  EXPECT_EQ(mode, "latest");
  EXPECT_EQ(out, "x");
  EXPECT_EQ(error_of(cli, {"prog", "--width", "0"}), "--width '0': must be 16..16384");
  EXPECT_EQ(error_of(cli, {"prog", "--width", "100000"}), "--width '100000': must be 16..16384");
  EXPECT_EQ(error_of(cli, {"prog", "--width", "12x"}), "--width '12x': not a whole number");
  EXPECT_EQ(error_of(cli, {"prog", "--pixel-error", "nan"}), "--pixel-error 'nan': not a finite number");
  EXPECT_EQ(error_of(cli, {"prog", "--bogus"}), "unknown flag --bogus (see prog --help)");
  EXPECT_EQ(error_of(cli, {"prog", "--camera-mode", "x"}), "--camera-mode 'x': expected one of latest|lockstep");
  EXPECT_EQ(error_of(cli, {"prog", "--out"}), "--out needs a value (DIR)");
  EXPECT_EQ(error_of(cli, {"prog", "stray"}), "unexpected argument 'stray' (see prog --help)");
  EXPECT_NE(cli.help().find("--camera-mode latest|lockstep"), std::string::npos);
}

// --help lists the options under their group's heading, the groups in CliGroup's order whatever
// the order of declaration, and leaves out headings without options; count() counts options.
TEST(Cli, HelpGroupsOptionsUnderHeadingsInOrder) {
  int width = 64, n = 0;
  std::string word = "a";
  Cli cli("prog", "[options]", "test");
  cli.option("n", &n, 0, 9, "expert by default");
  cli.group(CliGroup::accuracy);
  cli.option("width", &width, 16, 16384, "w");
  cli.group(CliGroup::scene);
  cli.custom("word", "a|b", "a", "custom", [&](const std::string& v) {
    if (v != "a" && v != "b") throw occ::InputError("--word '" + v + "': expected a or b");
    word = v;
  });
  EXPECT_EQ(cli.count(), 3u);
  const std::string h = cli.help();
  const size_t scene = h.find("\nscene and path:\n"), accuracy = h.find("\naccuracy:\n"), expert = h.find("\nexpert:\n");
  ASSERT_NE(scene, std::string::npos) << h;
  EXPECT_LT(scene, h.find("--word a|b"));
  EXPECT_LT(h.find("--word a|b"), accuracy);
  EXPECT_LT(accuracy, h.find("--width N"));
  EXPECT_LT(h.find("--width N"), expert);
  EXPECT_LT(expert, h.find("--n N"));
  EXPECT_EQ(h.find("output:"), std::string::npos) << h;
  EXPECT_NE(h.find("(default a)"), std::string::npos);
  Args b{"prog", "--word", "b"};
  ASSERT_TRUE(cli.parse(b.argc(), b.argv()));
  EXPECT_EQ(word, "b");
  EXPECT_EQ(error_of(cli, {"prog", "--word", "c"}), "--word 'c': expected a or b");
  EXPECT_THROW(cli.option("n", &n, 0, 9, "twice"), std::logic_error);
  EXPECT_EQ(Cli::whole("n", "7", 0, 9), 7);
  EXPECT_THROW(Cli::whole("n", "10", 0, 9), occ::InputError);
}

TEST(Cli, AWholeNumberOrAutoIsNulloptForAuto) {
  std::optional<int> hold;
  Cli cli("prog", "[options]", "test");
  cli.option("visibility-hold", &hold, 0, 255, "h");
  EXPECT_NE(cli.help().find("--visibility-hold N|auto"), std::string::npos);
  EXPECT_NE(cli.help().find("(default auto)"), std::string::npos);
  Args three{"prog", "--visibility-hold", "3"};
  ASSERT_TRUE(cli.parse(three.argc(), three.argv()));
  EXPECT_EQ(hold, 3);
  Args automatic{"prog", "--visibility-hold", "auto"};
  ASSERT_TRUE(cli.parse(automatic.argc(), automatic.argv()));
  EXPECT_EQ(hold, std::nullopt);
  EXPECT_EQ(error_of(cli, {"prog", "--visibility-hold", "x"}), "--visibility-hold 'x': not a whole number or auto");
  EXPECT_EQ(error_of(cli, {"prog", "--visibility-hold", "256"}), "--visibility-hold '256': must be 0..255 or auto");
}
