// cull_overview: the culling overview image of one frame. Runs the real binary on a small city,
// checks the PNG (size, the three category colours by hue) and that the printed counts cover
// every non-empty leaf of the hierarchy; that its replay holds the cluster's own visible sets;
// bad flags give one error line.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <regex>

#include "common/image.hpp"
#include "common/setup/scene_setup.hpp"
#include "cluster_run.hpp"
#include "integration_util.hpp"

using namespace occtest;
using namespace std::chrono_literals;

namespace {

Outcome run(std::vector<std::string> args, const fs::path& dir, const std::string& name) {
  return run_to_end(std::move(args), dir / (name + ".log"), 120s);
}

// Hue in degrees of a saturated, not too dark pixel, else -1.
double hue(const uint8_t* p) {
  const double r = p[0] / 255.0, g = p[1] / 255.0, b = p[2] / 255.0;
  const double mx = std::max({r, g, b}), mn = std::min({r, g, b}), d = mx - mn;
  if (mx < 0.12 || d / mx < 0.5) return -1;
  double h;
  if (mx == r)
    h = 60 * std::fmod((g - b) / d, 6.0);
  else if (mx == g)
    h = 60 * ((b - r) / d + 2);
  else
    h = 60 * ((r - g) / d + 4);
  return h < 0 ? h + 360 : h;
}

const char* kScene = "city:6x6:3:10:1";

}  // namespace

TEST(Overview, CityFrameHasAllThreeCategories) {
  fs::path dir = fresh_dir("overview");
  const fs::path png = dir / "sub" / "overview.png";
  Outcome o = run({bin("cull_overview"), "--scene", kScene, "--path", "walk:20", "--frame", "10", "--width", "160",
                   "--height", "120", "--view-width", "320", "--view-height", "240", "--out", png.string()},
                  dir, "city");
  ASSERT_EQ(o.code, 0) << o.log;
  ASSERT_TRUE(fs::exists(png)) << o.log;
  occ::Image img = occ::read_png(png.string());
  EXPECT_EQ(img.width, 320);
  EXPECT_EQ(img.height, 240);

  // Pixels by hue: yellow (visible), violet (frustum-culled), orange (occlusion-culled). The
  // legend's squares are 8x8 at this size: demand well more than that of each.
  size_t yellow = 0, violet = 0, orange = 0;
  for (size_t i = 0; i + 3 < img.rgba.size(); i += 4) {
    const double h = hue(&img.rgba[i]);
    if (h < 0) continue;
    if (h >= 42 && h <= 65) ++yellow;
    if (h >= 12 && h <= 36) ++orange;
    if (h >= 245 && h <= 290) ++violet;
  }
  EXPECT_GT(yellow, 200u) << "yellow " << yellow;
  EXPECT_GT(violet, 200u) << "violet " << violet;
  EXPECT_GT(orange, 200u) << "orange " << orange;

  // "cull_overview: frame 10: visible A, frustum-culled B, occlusion-culled C, leaves N, ..."
  std::smatch m;
  const std::regex line(R"(frame (\d+): visible (\d+), frustum-culled (\d+), occlusion-culled (\d+), leaves (\d+))");
  ASSERT_TRUE(std::regex_search(o.log, m, line)) << o.log;
  EXPECT_EQ(std::stoul(m[1]), 10u);
  const unsigned long visible = std::stoul(m[2]), frustum = std::stoul(m[3]), occluded = std::stoul(m[4]);
  EXPECT_GT(visible, 0u);
  EXPECT_GT(frustum, 0u);
  EXPECT_GT(occluded, 0u);

  // The same hierarchy built here: every non-empty leaf is in exactly one category.
  occ::SceneOptions so;
  so.spec = kScene;
  occ::LoadedScene ls = occ::load_and_build(so, "overview_test");
  size_t leaves = 0;
  for (const auto& n : ls.hierarchy.nodes())
    if (n.leaf() && n.item_count > 0) ++leaves;
  EXPECT_EQ(visible + frustum + occluded, leaves);
  EXPECT_EQ(std::stoul(m[5]), leaves);
}

TEST(Overview, BadFlagsGiveOneError) {
  fs::path dir = fresh_dir("overview_bad");
  auto one_error = [&](std::vector<std::string> args, const std::string& name, const std::string& fragment) {
    args.insert(args.begin(), bin("cull_overview"));
    expect_one_error(run(args, dir, name), {fragment});
  };
  const std::string out = (dir / "x.png").string();
  one_error({"--scene", kScene, "--path", "walk:20", "--frame", "20", "--out", out}, "frame", "--frame '20'");
  one_error({"--scene", kScene, "--path", "walk:20", "--frame", "-1", "--out", out}, "negative", "--frame '-1'");
  one_error({"--scene", kScene, "--path", "walk:20", "--frame", "3"}, "noout", "--out");
  one_error({"--scene", kScene, "--view-width", "0", "--out", out}, "vw", "--view-width '0'");
  one_error({"--bogus"}, "unknown", "--bogus");

  Outcome help = run({bin("cull_overview"), "--help"}, dir, "help");
  EXPECT_EQ(help.code, 0);
  EXPECT_NE(help.log.find("usage:"), std::string::npos) << help.log;
}

// The replay runs the switch nodes' own cull frames (switch_node/cull_frame.hpp), hold and
// adaptive queries included: at every frame shown, its visible set and its HC's queries are those
// of the real cluster on the same path (lockstep, occlusion on every frame: deterministic).
TEST(Overview, ReplaysTheClustersVisibleSetsAndQueries) {
  const fs::path dir = fresh_dir("overview_cluster");
  occtest::ClusterOptions o(kScene, "walk:20", {"--width", "160", "--height", "120"});
  o.client = {"--images", "off"};
  const occtest::ClusterRun r = occtest::run_cluster(dir / "cluster", o);
  ASSERT_EQ(r.rvg_code, 0) << r.logs();
  auto stats = read_csv(dir / "cluster" / "stats.csv");
  ASSERT_EQ(stats["visible"].size(), 20u);
  const std::regex line(R"(frame (\d+): visible (\d+), .* queries (\d+))");
  for (int f : {1, 6, 10, 19}) {
    Outcome ov = run({bin("cull_overview"), "--scene", kScene, "--path", "walk:20", "--frame", std::to_string(f), "--width",
                      "160", "--height", "120", "--view-width", "64", "--view-height", "48", "--out",
                      (dir / ("f" + std::to_string(f) + ".png")).string()},
                     dir, "frame" + std::to_string(f));
    ASSERT_EQ(ov.code, 0) << ov.log;
    std::smatch m;
    ASSERT_TRUE(std::regex_search(ov.log, m, line)) << ov.log;
    EXPECT_EQ(std::stod(m[2]), stats["visible"][size_t(f)]) << "frame " << f << ": |V|";
    EXPECT_EQ(std::stod(m[3]), stats["queries"][size_t(f)]) << "frame " << f << ": HC's queries";
  }
}
