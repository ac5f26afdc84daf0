// frame_diff DIR_A DIR_B [--threshold T] [--max-fraction F] [--psnr]
// frame_diff REFERENCE TAU --items [--tau T] [--check] [--slack S]
// Compares every frame_NNNNN.png of DIR_A with the same file in DIR_B. A pixel differs when any
// channel differs by more than T. Prints one line per frame and a summary line
//   frames=N differing_pixels=K max_frame_fraction=F
// With --psnr the summary goes on with  mean_fraction=M psnr_db=P  (PSNR over the RGB channels of
// all frames together: 10 log10(255^2 / MSE); "inf" when identical).
// With --items it compares the item buffers (items_NNNNN.png and items.txt, render_client
// --images items) of a full-detail reference and of a tau frame instead (item_diff.hpp): per
// frame the items missing, the largest displacement and the pixels beyond tau, and a summary
//   frames=N objects_missing=M max_displacement=D beyond_tau_fraction=F max_frame_beyond_tau_fraction=G
//   objects_missing_thick=K max_thick_displacement=T thin_fraction=S
// Exit: 0 ok, 1 a frame is missing in B / sizes differ / no frames / unreadable file,
//       2 usage error, 3 some frame's differing fraction exceeds --max-fraction (--items --check:
//       a frame misses an object or has a pixel displaced by more than tau + slack).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <string>
#include <vector>

#include "common/cli.hpp"
#include "common/error.hpp"
#include "common/image.hpp"
#include "render_client/tools/item_diff.hpp"

namespace fs = std::filesystem;

namespace {

bool is_frame_file(const std::string& name, const std::string& prefix = "frame_") {  // prefix + digits + .png
  const std::string suffix = ".png";
  if (name.size() <= prefix.size() + suffix.size() || name.rfind(prefix, 0) != 0 ||
      name.compare(name.size() - suffix.size(), suffix.size(), suffix) != 0)
    return false;
  return std::all_of(name.begin() + prefix.size(), name.end() - suffix.size(),
                     [](char c) { return c >= '0' && c <= '9'; });
}

// Sum of squared RGB differences.
double squared_error(const occ::Image& a, const occ::Image& b) {
  double s = 0;
  for (size_t p = 0; p < a.rgba.size(); p += 4)
    for (size_t c = 0; c < 3; ++c) {
      const double d = double(a.rgba[p + c]) - double(b.rgba[p + c]);
      s += d * d;
    }
  return s;
}

uint64_t count_differing(const occ::Image& a, const occ::Image& b, int threshold) {
  uint64_t n = 0;
  for (size_t p = 0; p < a.rgba.size(); p += 4)
    for (size_t c = 0; c < 4; ++c)
      if (std::abs(int(a.rgba[p + c]) - int(b.rgba[p + c])) > threshold) {
        ++n;
        break;
      }
  return n;
}

struct ItemsOptions {
  double tau = 0, slack = 1;
  bool check = false, thick = false;
};

// --items: the item buffers of REFERENCE and TAU (item_diff.hpp).
int run_items(const std::vector<std::string>& dirs, const ItemsOptions& o) {
  const occ::ItemSpace space = occ::ItemSpace::read((fs::path(dirs[0]) / "items.txt").string());
  if (!(occ::ItemSpace::read((fs::path(dirs[1]) / "items.txt").string()) == space))
    throw std::runtime_error("items.txt of " + dirs[0] + " and " + dirs[1] + " differ (not the same scene)");
  std::vector<std::string> names;
  for (const auto& entry : fs::directory_iterator(dirs[0]))
    if (entry.is_regular_file() && is_frame_file(entry.path().filename().string(), "items_"))
      names.push_back(entry.path().filename().string());
  std::sort(names.begin(), names.end());
  if (names.empty()) throw std::runtime_error(dirs[0] + ": no items_NNNNN.png files (render_client --images items)");
  uint64_t missing = 0, missing_thick = 0, beyond = 0, pixels = 0;
  double worst = 0, worst_fraction = 0, worst_thick = 0;
  uint64_t thin = 0;
  bool broken = false;
  for (const std::string& name : names) {
    const fs::path path_b = fs::path(dirs[1]) / name;
    if (!fs::exists(path_b)) throw std::runtime_error(path_b.string() + ": missing (present in " + dirs[0] + ")");
    occ::IdImage ids[2];
    for (int k = 0; k < 2; ++k) {
      ids[k] = occ::decode_ids(occ::read_png((fs::path(dirs[k]) / name).string()));
      const fs::path depth = fs::path(dirs[k]) / ("depth_" + name.substr(6));
      if (fs::exists(depth)) ids[k].depth = occ::decode_depth(occ::read_png(depth.string()));
    }
    const occ::ItemDiff d = occ::diff_items(space, ids[0], ids[1], o.tau);
    const double fraction = double(d.beyond_tau) / double(d.pixels);
    std::printf("frame %s: shown=%llu missing=%llu max_displacement=%.3f at (%d,%d) beyond_tau=%llu (%.4f%%) "
                "max_thick_displacement=%.3f at (%d,%d) thin_pixels=%llu",
                name.substr(6, name.size() - 10).c_str(), (unsigned long long)d.shown, (unsigned long long)d.missing,
                d.max_displacement, d.worst_x, d.worst_y, (unsigned long long)d.beyond_tau, 100.0 * fraction,
                d.max_thick_displacement, d.thick_x, d.thick_y, (unsigned long long)d.thin);
    if (d.missing)
      std::printf(" missing_thick=%llu missing_pixels=%llu first_missing_item=%u at (%d,%d)",
                  (unsigned long long)d.missing_thick, (unsigned long long)d.missing_pixels, d.first_missing, d.missing_x,
                  d.missing_y);
    std::printf("\n");
    missing += d.missing;
    missing_thick += d.missing_thick;
    beyond += d.beyond_tau;
    pixels += d.pixels;
    worst = std::max(worst, d.max_displacement);
    worst_thick = std::max(worst_thick, d.max_thick_displacement);
    thin += d.thin;
    worst_fraction = std::max(worst_fraction, fraction);
    broken = broken || (o.thick ? d.missing_thick : d.missing) > 0 ||
             (o.thick ? d.max_thick_displacement : d.max_displacement) > o.tau + o.slack;
  }
  std::printf("frames=%zu objects_missing=%llu max_displacement=%.3f beyond_tau_fraction=%.6g "
              "max_frame_beyond_tau_fraction=%.6g objects_missing_thick=%llu max_thick_displacement=%.3f "
              "thin_fraction=%.6g\n",
              names.size(), (unsigned long long)missing, worst, double(beyond) / double(pixels), worst_fraction,
              (unsigned long long)missing_thick, worst_thick, double(thin) / double(pixels));
  std::fflush(stdout);
  if (o.check && broken) {
    std::cerr << "error: the promise is broken: " << missing << " objects missing, displacement up to " << worst
              << " px (--tau " << o.tau << " + --slack " << o.slack << ")\n";
    return 3;
  }
  return 0;
}

int run(int argc, char** argv) {
  // Leading non-flag arguments are the two directories; the rest are options.
  std::vector<std::string> dirs;
  int first_option = 1;
  while (first_option < argc && argv[first_option][0] != '-') dirs.push_back(argv[first_option++]);
  int threshold = 0;
  double max_fraction = 1.0;
  occ::Cli cli("frame_diff", "DIR_A DIR_B [options]",
               "Compares the frame_NNNNN.png files of DIR_A with those of DIR_B, pixel by pixel.\n"
               "Exit 1 when a frame is missing in DIR_B, sizes differ or DIR_A has no frames;\n"
               "2 on usage errors; 3 when a frame's differing fraction exceeds --max-fraction.");
  cli.option("threshold", &threshold, 0, 255, "a pixel differs if any channel differs by more than this");
  cli.option("max-fraction", &max_fraction, 0.0, 1.0, "exit 3 if a frame's differing fraction exceeds this");
  bool psnr = false, items = false;
  cli.flag("psnr", &psnr, "also print the mean differing fraction and the PSNR (dB) of all frames");
  ItemsOptions io;
  cli.flag("items", &items, "compare the item buffers (render_client --images items): DIR_A the full-detail "
                            "reference, DIR_B the tau frames");
  cli.option("tau", &io.tau, 0.0, 1e6, "--items: the pixel error the frames were drawn with (pixels beyond it count)");
  cli.option("slack", &io.slack, 0.0, 1e6, "--items --check: displacement allowed beyond tau (rasterisation)");
  cli.flag("thick", &io.thick, "--items --check: bound objects_missing_thick and max_thick_displacement "
                               "(slivers at most two pixels thick excused)");
  cli.flag("check", &io.check, "--items: exit 3 when a frame misses an object or displaces a pixel by more than "
                               "tau + slack");
  std::vector<char*> rest{argv[0]};
  rest.insert(rest.end(), argv + first_option, argv + argc);
  if (!cli.parse(int(rest.size()), rest.data())) return 0;
  if (dirs.size() != 2)
    throw occ::InputError("expected two directories DIR_A DIR_B, got " + std::to_string(dirs.size()) +
                          " (see frame_diff --help)");
  for (const std::string& d : dirs)
    if (!fs::is_directory(d)) throw occ::InputError("'" + d + "': not a directory");
  if (items) return run_items(dirs, io);

  std::vector<std::string> names;
  for (const auto& entry : fs::directory_iterator(dirs[0]))
    if (entry.is_regular_file() && is_frame_file(entry.path().filename().string()))
      names.push_back(entry.path().filename().string());
  std::sort(names.begin(), names.end());
  if (names.empty()) throw std::runtime_error(dirs[0] + ": no frame_NNNNN.png files");

  uint64_t total = 0;
  double worst = 0.0, sum_fraction = 0.0, sq = 0.0, samples = 0.0;
  for (const std::string& name : names) {
    const fs::path path_b = fs::path(dirs[1]) / name;
    if (!fs::exists(path_b)) throw std::runtime_error(path_b.string() + ": missing (present in " + dirs[0] + ")");
    const occ::Image a = occ::read_png((fs::path(dirs[0]) / name).string());
    const occ::Image b = occ::read_png(path_b.string());
    if (a.width != b.width || a.height != b.height)
      throw std::runtime_error(name + ": sizes differ (" + std::to_string(a.width) + "x" +
                               std::to_string(a.height) + " vs " + std::to_string(b.width) + "x" +
                               std::to_string(b.height) + ")");
    const uint64_t n = count_differing(a, b, threshold);
    const double fraction = double(n) / (double(a.width) * a.height);
    total += n;
    worst = std::max(worst, fraction);
    sum_fraction += fraction;
    if (psnr) {
      sq += squared_error(a, b);
      samples += 3.0 * double(a.width) * a.height;
    }
    const std::string frame = name.substr(6, name.size() - 10);
    std::printf("frame %s: %llu differing pixels (%.4f%%)\n", frame.c_str(), (unsigned long long)n,
                100.0 * fraction);
  }
  std::printf("frames=%zu differing_pixels=%llu max_frame_fraction=%.6g", names.size(), (unsigned long long)total,
              worst);
  if (psnr) {
    const double mse = samples > 0 ? sq / samples : 0.0;
    std::printf(" mean_fraction=%.6g", sum_fraction / double(names.size()));
    if (mse > 0)
      std::printf(" psnr_db=%.3f", 10.0 * std::log10(255.0 * 255.0 / mse));
    else
      std::printf(" psnr_db=inf");
  }
  std::printf("\n");
  std::fflush(stdout);
  if (worst > max_fraction) {
    std::cerr << "error: a frame differs in " << worst << " of its pixels (--max-fraction " << max_fraction << ")\n";
    return 3;
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  return occ::run_main([&] { return run(argc, argv); });
}
