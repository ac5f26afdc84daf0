// frame_diff DIR_A DIR_B [--threshold T] [--max-fraction F] [--psnr]
// Compares every frame_NNNNN.png of DIR_A with the same file in DIR_B. A pixel differs when any
// channel differs by more than T. Prints one line per frame and a summary line
//   frames=N differing_pixels=K max_frame_fraction=F
// With --psnr the summary goes on with  mean_fraction=M psnr_db=P  (PSNR over the RGB channels of
// all frames together: 10 log10(255^2 / MSE); "inf" when identical).
// Exit: 0 ok, 1 a frame is missing in B / sizes differ / no frames / unreadable file,
//       2 usage error, 3 some frame's differing fraction exceeds --max-fraction.
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

namespace fs = std::filesystem;

namespace {

bool is_frame_file(const std::string& name) {  // frame_ + digits + .png
  const std::string prefix = "frame_", suffix = ".png";
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
  bool psnr = false;
  cli.flag("psnr", &psnr, "also print the mean differing fraction and the PSNR (dB) of all frames");
  std::vector<char*> rest{argv[0]};
  rest.insert(rest.end(), argv + first_option, argv + argc);
  if (!cli.parse(int(rest.size()), rest.data())) return 0;
  if (dirs.size() != 2)
    throw occ::InputError("expected two directories DIR_A DIR_B, got " + std::to_string(dirs.size()) +
                          " (see frame_diff --help)");
  for (const std::string& d : dirs)
    if (!fs::is_directory(d)) throw occ::InputError("'" + d + "': not a directory");

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
