// Writes the fuzzers' seed inputs (fuzz_targets.hpp), made by the repository's own writers:
//   gltf/         walls.gltf, walls.glb (hard:walls:1 through save_gltf, the buffer embedded),
//                 features.gltf, features.glb (materials, a texture, TRS and child nodes,
//                 COLOR_0, TEXCOORD_0, byte indices, a strip and a line primitive)
//   camera_path/  orbit.csv (save_camera_path), by_hand.csv (11 columns, comments, CRLF)
//   scene_cache/  walls.scene (the fixture), features.scene (features.gltf: materials, images)
//   lod_cache/    walls.lod (the fixture's LODs)
//   web_input/    input_N.txt: one render_client --web input message each, every kind (format_web_input)
//   ply/          walls.ply, walls_ascii.ply (the fixture through model_files.hpp's writer, with
//                 normals and colours), by_hand.ply (ASCII: a quad, float colours, a list in the
//                 vertex element, an element of its own)
//   obj/          walls.obj (the fixture through model_files.hpp's writer, without its MTL),
//                 by_hand.obj (groups, a quad, texture coordinates, negative indices, a line)
// Usage: make_fuzz_seeds DIR (the checked-in seeds are in tests/fuzz/). Run it again when a cache
// format version changes: the seeds test (tests/fuzz_parsers_test.cpp) fails on stale seeds.
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>

#include "common/camera_path.hpp"
#include "common/web_input.hpp"
#include "common/error.hpp"
#include "common/fuzz/fuzz_targets.hpp"
#include "common/image.hpp"
#include "common/lod/lod_cache.hpp"
#include "common/scene/scene_cache.hpp"
#include "common/scene/scene_io.hpp"
#include "model_files.hpp"
#include "render_client/tools/scene_export.hpp"

namespace fs = std::filesystem;
using nlohmann::json;
using namespace occ;
using namespace occ::fuzz;

namespace {

std::vector<uint8_t> read_bytes(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void write_bytes(const fs::path& p, const void* data, size_t n) {
  std::ofstream out(p, std::ios::binary | std::ios::trunc);
  out.write(static_cast<const char*>(data), std::streamsize(n));
  if (!out) throw InputError(p.string() + ": cannot write");
}
void write_text(const fs::path& p, const std::string& s) { write_bytes(p, s.data(), s.size()); }

std::string base64(const std::vector<uint8_t>& b) {
  static const char* k = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string s;
  for (size_t i = 0; i < b.size(); i += 3) {
    const uint32_t v = uint32_t(b[i]) << 16 | (i + 1 < b.size() ? uint32_t(b[i + 1]) << 8 : 0) |
                       (i + 2 < b.size() ? b[i + 2] : 0);
    s += k[v >> 18 & 63];
    s += k[v >> 12 & 63];
    s += i + 1 < b.size() ? k[v >> 6 & 63] : '=';
    s += i + 2 < b.size() ? k[v & 63] : '=';
  }
  return s;
}

std::string data_uri(const std::vector<uint8_t>& b, const char* mime) {
  return std::string("data:") + mime + ";base64," + base64(b);
}

// A GLB container: 12-byte header, the JSON chunk, the BIN chunk (each padded to 4 bytes).
std::vector<uint8_t> glb(std::string text, std::vector<uint8_t> bin) {
  while (text.size() % 4) text += ' ';
  while (bin.size() % 4) bin.push_back(0);
  std::vector<uint8_t> out;
  auto u32 = [&](uint32_t v) {
    for (int i = 0; i < 4; ++i) out.push_back(uint8_t(v >> (8 * i)));
  };
  out.insert(out.end(), {'g', 'l', 'T', 'F'});
  u32(2);
  u32(uint32_t(12 + 8 + text.size() + 8 + bin.size()));
  u32(uint32_t(text.size()));
  u32(0x4E4F534A);  // JSON
  out.insert(out.end(), text.begin(), text.end());
  u32(uint32_t(bin.size()));
  u32(0x004E4942);  // BIN
  out.insert(out.end(), bin.begin(), bin.end());
  return out;
}

template <class T>
size_t append(std::vector<uint8_t>& bin, const std::vector<T>& v) {
  while (bin.size() % 4) bin.push_back(0);
  const size_t at = bin.size();
  const auto* p = reinterpret_cast<const uint8_t*>(v.data());
  bin.insert(bin.end(), p, p + v.size() * sizeof(T));
  return at;
}

// hard:walls:1 as save_gltf writes it, its buffer embedded (a data URI) and as a GLB.
void walls_gltf(const fs::path& dir, const fs::path& tmp) {
  save_gltf(fixture().scene, (tmp / "walls.gltf").string());
  json g = json::parse(read_bytes(tmp / "walls.gltf"));
  const std::vector<uint8_t> bin = read_bytes(tmp / "walls.bin");
  g["buffers"][0]["uri"] = data_uri(bin, "application/octet-stream");
  write_text(dir / "walls.gltf", g.dump());
  g["buffers"][0].erase("uri");
  const auto b = glb(g.dump(), bin);
  write_bytes(dir / "walls.glb", b.data(), b.size());
}

// A small file with what save_gltf leaves out: materials (texture, MASK, BLEND, unlit), a
// sampler, node TRS and children, COLOR_0 and TEXCOORD_0, byte indices, a strip, a line.
json features(std::vector<uint8_t>& bin, const std::vector<uint8_t>& png, bool image_in_buffer) {
  const std::vector<float> pos = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0};
  const std::vector<float> uv = {0, 1, 1, 1, 1, 0, 0, 0};
  const std::vector<uint8_t> col = {255, 0, 0, 255, 0, 255, 0, 255, 0, 0, 255, 255, 255, 255, 255, 128};
  const std::vector<uint8_t> idx = {0, 1, 2, 0, 2, 3};
  const std::vector<uint16_t> strip = {0, 1, 3, 2};
  json views = json::array(), acc = json::array();
  auto view = [&](size_t at, size_t n) {
    views.push_back({{"buffer", 0}, {"byteOffset", at}, {"byteLength", n}});
    return views.size() - 1;
  };
  acc.push_back({{"bufferView", view(append(bin, pos), 48)}, {"componentType", 5126}, {"count", 4}, {"type", "VEC3"},
                 {"min", {0, 0, 0}}, {"max", {1, 1, 0}}});
  acc.push_back({{"bufferView", view(append(bin, uv), 32)}, {"componentType", 5126}, {"count", 4}, {"type", "VEC2"}});
  acc.push_back({{"bufferView", view(append(bin, col), 16)}, {"componentType", 5121}, {"normalized", true},
                 {"count", 4}, {"type", "VEC4"}});
  acc.push_back({{"bufferView", view(append(bin, idx), 6)}, {"componentType", 5121}, {"count", 6}, {"type", "SCALAR"}});
  acc.push_back({{"bufferView", view(append(bin, strip), 8)}, {"componentType", 5123}, {"count", 4}, {"type", "SCALAR"}});
  json image = {{"mimeType", "image/png"}};
  if (image_in_buffer)
    image["bufferView"] = view(append(bin, png), png.size());
  else
    image["uri"] = data_uri(png, "image/png");
  const json attrs = {{"POSITION", 0}, {"TEXCOORD_0", 1}, {"COLOR_0", 2}};
  json g = {
      {"asset", {{"version", "2.0"}}},
      {"extensionsUsed", {"KHR_materials_unlit"}},
      {"scene", 0},
      {"scenes", {{{"nodes", {0}}}}},
      {"nodes",
       {{{"translation", {1, 2, 3}}, {"rotation", {0, 0.7071068, 0, 0.7071068}}, {"scale", {2, 2, 2}}, {"children", {1, 2}}},
        {{"mesh", 0}, {"name", "quad"}},
        {{"mesh", 1}, {"matrix", {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 5, 0, 0, 1}}}}},
      {"meshes",
       {{{"primitives", {{{"attributes", attrs}, {"indices", 3}, {"material", 0}}}}},
        {{"primitives",
          {{{"attributes", attrs}, {"indices", 4}, {"material", 1}, {"mode", 5}},
           {{"attributes", {{"POSITION", 0}}}, {"mode", 1}}}}}}},
      {"materials",
       {{{"name", "textured"}, {"alphaMode", "MASK"}, {"alphaCutoff", 0.3}, {"doubleSided", true},
         {"pbrMetallicRoughness", {{"baseColorFactor", {1, 0.5, 0.5, 1}}, {"baseColorTexture", {{"index", 0}}}}}},
        {{"name", "glass"}, {"alphaMode", "BLEND"}, {"extensions", {{"KHR_materials_unlit", json::object()}}},
         {"pbrMetallicRoughness", {{"baseColorFactor", {0.2, 0.4, 1, 0.5}}}}}}},
      {"textures", {{{"source", 0}, {"sampler", 0}}}},
      {"samplers", {{{"magFilter", 9728}, {"minFilter", 9987}, {"wrapS", 33071}, {"wrapT", 33648}}}},
      {"images", {image}},
      {"accessors", acc},
      {"bufferViews", views},
  };
  return g;
}

void features_gltf(const fs::path& dir, const fs::path& tmp) {
  Image img;
  img.width = img.height = 2;
  img.rgba = {255, 0, 0, 255, 0, 255, 0, 255, 0, 0, 255, 255, 255, 255, 255, 255};
  write_png((tmp / "2x2.png").string(), img);
  const std::vector<uint8_t> png = read_bytes(tmp / "2x2.png");
  std::vector<uint8_t> bin;
  json g = features(bin, png, false);
  g["buffers"] = {{{"byteLength", bin.size()}, {"uri", data_uri(bin, "application/octet-stream")}}};
  write_text(dir / "features.gltf", g.dump());
  bin.clear();
  g = features(bin, png, true);
  g["buffers"] = {{{"byteLength", bin.size()}}};
  const auto b = glb(g.dump(), bin);
  write_bytes(dir / "features.glb", b.data(), b.size());
}

void camera_paths(const fs::path& dir) {
  const Aabb bounds{{-10, 0, -10}, {10, 5, 10}};
  save_camera_path((dir / "orbit.csv").string(), load_camera_path("orbit:4", bounds, Viewport{64, 48}));
  write_text(dir / "by_hand.csv",
             "# a path written by hand\r\n"
             "frame,eye_x,eye_y,eye_z,target_x,target_y,target_z,up_x,up_y,up_z,fovy_deg\r\n"
             "0, 0, 1.7, -8, 0, 1.7, 0, 0, 1, 0, 60\r\n"
             "\r\n"
             "# turning left\r\n"
             "1,0.5,1.7,-7.5,-1e1,1.7,0,0,1,0,45.5\r\n"
             "2,1,1.7,-7,-10,1.7,0,0,1,0,90,0.01,100\r\n");
}

// One input message a file, as the page sends them (format_web_input), every kind.
void web_inputs(const fs::path& dir) {
  using K = WebInput::Kind;
  const WebInput inputs[] = {{1, K::key_down, WebKey::w},
                             {2, K::key_up, WebKey::shift},
                             {3, K::button_down, WebKey::none, 1, 120, 64},
                             {4, K::motion, WebKey::none, 0, -35, 99999},
                             {5, K::button_up, WebKey::none, 3, 0, 0},
                             {6, K::wheel, WebKey::none, 0, 0, 0, -2},
                             {7, K::blur},
                             {2147483647, K::quit},
                             {8, K::ping}};
  for (const WebInput& in : inputs) write_text(dir / ("input_" + std::to_string(in.seq % 100) + ".txt"), format_web_input(in));
}

void caches(const fs::path& root, const fs::path& gltf_dir) {
  const Fixture& f = fixture();
  auto must = [](const std::optional<std::string>& err) {
    if (err) throw InputError(*err);
  };
  must(save_scene_cache((root / "scene_cache" / "walls.scene").string(),
                        scene_cache_key("hard:walls:1", kFixtureBuild), f.scene, f.hierarchy));
  Scene s = load_gltf((gltf_dir / "features.gltf").string());
  s.source = "features.gltf";  // not the folder it was written to: the same seed from any folder
  s.files.clear();             // (nor its files, which a reader would find gone: a stale cache)
  const Hierarchy h = Hierarchy::build(s, kFixtureBuild);
  must(save_scene_cache((root / "scene_cache" / "features.scene").string(),
                        scene_cache_key("features.gltf", kFixtureBuild), s, h));
  const LodData lod = LodData::build(f.scene, f.hierarchy, LodParams{});
  must(lod.save((root / "lod_cache" / "walls.lod").string()));
}

void models(const fs::path& root, const fs::path& tmp) {
  const Scene& s = fixture().scene;
  occtest::write_ply(s, (root / "ply" / "walls.ply").string(), true, true);
  occtest::write_ply(s, (root / "ply" / "walls_ascii.ply").string(), false, true);
  write_text(root / "ply" / "by_hand.ply",
             "ply\nformat ascii 1.0\ncomment written by hand\nelement vertex 4\nproperty float x\n"
             "property float y\nproperty float z\nproperty list uchar int extra\nproperty float red\n"
             "property float green\nproperty float blue\nelement face 1\nproperty list uchar int vertex_indices\n"
             "element camera 1\nproperty float view_px\nend_header\n"
             "0 0 0 0 1 0 0\n1 0 0 1 7 0 1 0\n1 1 0 2 7 7 0 0 1\n0 1 0 0 0.5 0.5 0.5\n4 0 1 2 3\n2.5\n");
  occtest::write_obj(s, (tmp / "walls.obj").string());
  std::string obj;
  {
    std::ifstream in(tmp / "walls.obj");
    for (std::string line; std::getline(in, line);)
      if (line.rfind("mtllib", 0) != 0 && line.rfind("usemtl", 0) != 0) obj += line + "\n";
  }
  write_text(root / "obj" / "walls.obj", obj);
  write_text(root / "obj" / "by_hand.obj",
             "# written by hand\ng front\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\n"
             "vn 0 0 1\nf 1/1/1 2/2/1 3/3/1 4/1/1\ng back\nv 0 0 -1\nv 1 0 -1\nv 1 1 -1\n"
             "f -1//1 -2//1 -3//1\nl 1 2\n");
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: make_fuzz_seeds DIR\n");
    return 2;
  }
  try {
    const fs::path root = argv[1];
    const fs::path tmp = fs::temp_directory_path() / ("occ_seeds." + std::to_string(::getpid()));
    for (const char* d : {"gltf", "camera_path", "scene_cache", "lod_cache", "ply", "obj", "web_input"})
      fs::create_directories(root / d);
    fs::create_directories(tmp);
    walls_gltf(root / "gltf", tmp);
    features_gltf(root / "gltf", tmp);
    camera_paths(root / "camera_path");
    caches(root, root / "gltf");
    web_inputs(root / "web_input");
    models(root, tmp);
    fs::remove_all(tmp);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
  return 0;
}
