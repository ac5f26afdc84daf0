// write_model SPEC OUT.ply|OUT.obj|OUT.stl [ascii]: the scene of a --scene spec (plant:13 ...)
// written as a model file (model_files.hpp; PLY binary unless `ascii`, with vertex colours), to
// generate big models for measurements instead of shipping them.
// write_model read FILE: FILE read by load_model, and by Assimp as well (load_with_assimp), with the
// time of each and the counts read, to compare the readers side by side (run each under
// /usr/bin/time -v for its memory: `write_model read-assimp FILE` reads with Assimp only,
// `write_model read-own FILE` with load_model only).
#include <chrono>
#include <cstdio>
#include <iostream>

#include "common/error.hpp"
#include "common/scene/assimp_reader.hpp"
#include "common/scene/model_reader.hpp"
#include "common/scene/scene_io.hpp"
#include "model_files.hpp"

namespace {

bool ends_with(const std::string& s, const std::string& e) {
  return s.size() >= e.size() && s.compare(s.size() - e.size(), e.size(), e) == 0;
}

void read_with(const char* who, occ::Scene (*read)(const std::string&), const std::string& file) {
  const auto t0 = std::chrono::steady_clock::now();
  const occ::Scene s = read(file);
  const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  uint64_t v = 0;
  for (const occ::Mesh& m : s.meshes) v += m.positions.size();
  std::printf("%s: %s: %zu objects, %zu meshes, %.3f M triangles, %.3f M vertices, read in %.0f ms\n", who,
              file.c_str(), s.objects.size(), s.meshes.size(), s.triangle_count() / 1e6, v / 1e6, ms);
}

}  // namespace

int main(int argc, char** argv) {
  const std::string usage =
      "usage: write_model SPEC OUT.ply|OUT.obj|OUT.stl [ascii]  |  write_model read|read-own|read-assimp FILE\n";
  if (argc < 3) {
    std::cerr << usage;
    return 2;
  }
  try {
    const std::string a = argv[1], b = argv[2];
    if (a == "read" || a == "read-own") read_with("load_model", occ::load_model, b);
    if (a == "read" || a == "read-assimp") read_with("load_with_assimp", occ::load_with_assimp, b);
    if (a == "read" || a == "read-own" || a == "read-assimp") return 0;
    const occ::Scene s = occ::load_scene(a);
    const bool ascii = argc > 3 && std::string(argv[3]) == "ascii";
    if (ends_with(b, ".ply")) occtest::write_ply(s, b, !ascii, true);
    else if (ends_with(b, ".obj")) occtest::write_obj(s, b);
    else if (ends_with(b, ".stl")) occtest::write_stl(s, b);
    else throw std::runtime_error(b + ": expected .ply, .obj or .stl");
    std::printf("wrote %s: %.3f M triangles\n", b.c_str(), s.triangle_count() / 1e6);
  } catch (const std::exception& e) {
    std::cerr << "error: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
