// Small glTF 2.0 files with materials, written by the material tests: unit quads and boxes,
// materials as JSON, PNG textures embedded in the binary chunk, nodes with TRS; saved as .glb.
#pragma once
#include <unistd.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <glm/glm.hpp>
#include <nlohmann/json.hpp>

#include "common/image.hpp"

namespace mattest {

namespace fs = std::filesystem;
using nlohmann::json;

inline std::vector<unsigned char> read_bytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), {}};
}

// Solid RGBA8 image, w x h, every texel `rgba`.
inline occ::Image solid(int w, int h, std::array<uint8_t, 4> rgba) {
  occ::Image img;
  img.width = w;
  img.height = h;
  for (int i = 0; i < w * h; ++i) img.rgba.insert(img.rgba.end(), rgba.begin(), rgba.end());
  return img;
}

inline void set_texel(occ::Image& img, int x, int y, std::array<uint8_t, 4> rgba) {
  std::copy(rgba.begin(), rgba.end(), img.rgba.begin() + (size_t(y) * img.width + x) * 4);
}

struct GltfBuilder {
  json j = {{"asset", {{"version", "2.0"}}}, {"bufferViews", json::array()}, {"accessors", json::array()},
            {"meshes", json::array()}, {"materials", json::array()}, {"nodes", json::array()}};
  std::vector<unsigned char> bin;
  fs::path scratch;  // for PNG encoding

  explicit GltfBuilder(fs::path scratch_dir) : scratch(std::move(scratch_dir)) {}

  int view(const void* data, size_t bytes) {
    bin.resize((bin.size() + 3) / 4 * 4);
    j["bufferViews"].push_back({{"buffer", 0}, {"byteOffset", bin.size()}, {"byteLength", bytes}});
    const auto* p = static_cast<const unsigned char*>(data);
    bin.insert(bin.end(), p, p + bytes);
    return int(j["bufferViews"].size() - 1);
  }
  template <class T>
  int accessor(const std::vector<T>& data, int component_type, size_t count, const char* type, bool normalized = false) {
    json a = {{"bufferView", view(data.data(), data.size() * sizeof(T))}, {"componentType", component_type},
              {"count", count}, {"type", type}};
    if (normalized) a["normalized"] = true;
    j["accessors"].push_back(a);
    return int(j["accessors"].size() - 1);
  }
  int material(json m) {
    j["materials"].push_back(std::move(m));
    return int(j["materials"].size() - 1);
  }
  // A texture of `img` (PNG in the binary chunk) with the given sampler JSON (empty: none).
  int texture(const occ::Image& img, json sampler = json()) {
    const fs::path png = scratch / ("tex_" + std::to_string(j.value("images", json::array()).size()) + ".png");
    occ::write_png(png.string(), img);
    const std::vector<unsigned char> bytes = read_bytes(png);
    if (!j.contains("images")) j["images"] = json::array();
    if (!j.contains("textures")) j["textures"] = json::array();
    j["images"].push_back({{"bufferView", view(bytes.data(), bytes.size())}, {"mimeType", "image/png"}});
    json t = {{"source", int(j["images"].size() - 1)}};
    if (!sampler.is_null()) {
      if (!j.contains("samplers")) j["samplers"] = json::array();
      j["samplers"].push_back(sampler);
      t["sampler"] = int(j["samplers"].size() - 1);
    }
    j["textures"].push_back(t);
    return int(j["textures"].size() - 1);
  }
  // Unit quad in the XY plane centred on the origin, front (CCW) facing +Z, normals +Z; uv (0, 0)
  // at its top-left corner (-0.5, +0.5) as seen from +Z. colors: 4 RGBA floats per vertex in the
  // order (-,-) (+,-) (+,+) (-,+), or empty.
  int quad(int material, bool uvs = false, const std::vector<float>& colors = {}) {
    const std::vector<float> pos = {-0.5f, -0.5f, 0, 0.5f, -0.5f, 0, 0.5f, 0.5f, 0, -0.5f, 0.5f, 0};
    const std::vector<float> nrm = {0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1};
    const std::vector<uint16_t> idx = {0, 1, 2, 0, 2, 3};
    json attrs = {{"POSITION", accessor(pos, 5126, 4, "VEC3")}, {"NORMAL", accessor(nrm, 5126, 4, "VEC3")}};
    if (uvs) attrs["TEXCOORD_0"] = accessor(std::vector<float>{0, 1, 1, 1, 1, 0, 0, 0}, 5126, 4, "VEC2");
    if (!colors.empty()) attrs["COLOR_0"] = accessor(colors, 5126, 4, "VEC4");
    json prim = {{"attributes", attrs}, {"indices", accessor(idx, 5123, 6, "SCALAR")}};
    if (material >= 0) prim["material"] = material;
    j["meshes"].push_back({{"primitives", {prim}}});
    return int(j["meshes"].size() - 1);
  }
  // Unit cube [-0.5, 0.5]^3, faces wound CCW from outside, flat normals.
  int box(int material) {
    std::vector<float> pos, nrm;
    std::vector<uint16_t> idx;
    const glm::vec3 axes[3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    for (int a = 0; a < 3; ++a)
      for (float s : {-1.0f, 1.0f}) {
        const glm::vec3 n = axes[a] * s, u = axes[(a + 1) % 3], v = axes[(a + 2) % 3] * s;  // u x v = n
        const auto base = uint16_t(pos.size() / 3);
        for (glm::vec2 c : {glm::vec2(-1, -1), glm::vec2(1, -1), glm::vec2(1, 1), glm::vec2(-1, 1)}) {
          const glm::vec3 p = 0.5f * (n + c.x * u + c.y * v);
          pos.insert(pos.end(), {p.x, p.y, p.z});
          nrm.insert(nrm.end(), {n.x, n.y, n.z});
        }
        idx.insert(idx.end(), {base, uint16_t(base + 1), uint16_t(base + 2), base, uint16_t(base + 2), uint16_t(base + 3)});
      }
    json prim = {{"attributes", {{"POSITION", accessor(pos, 5126, pos.size() / 3, "VEC3")},
                                 {"NORMAL", accessor(nrm, 5126, nrm.size() / 3, "VEC3")}}},
                 {"indices", accessor(idx, 5123, idx.size(), "SCALAR")}};
    if (material >= 0) prim["material"] = material;
    j["meshes"].push_back({{"primitives", {prim}}});
    return int(j["meshes"].size() - 1);
  }
  // A root node drawing `mesh` at translation t with scale s and rotation q (x, y, z, w).
  void node(int mesh, glm::dvec3 t, glm::dvec3 s = glm::dvec3(1.0), glm::dvec4 q = glm::dvec4(0, 0, 0, 1)) {
    j["nodes"].push_back({{"mesh", mesh}, {"translation", {t.x, t.y, t.z}}, {"scale", {s.x, s.y, s.z}},
                          {"rotation", {q.x, q.y, q.z, q.w}}});
  }
  // Writes the .glb container (all nodes in scene 0) and returns its path.
  std::string write_glb(const fs::path& path) {
    json doc = j;
    doc["scenes"] = {{{"nodes", json::array()}}};
    for (size_t n = 0; n < j["nodes"].size(); ++n) doc["scenes"][0]["nodes"].push_back(n);
    doc["scene"] = 0;
    if (doc["materials"].empty()) doc.erase("materials");
    std::vector<unsigned char> b = bin;
    doc["buffers"] = {{{"byteLength", b.size()}}};
    std::string text = doc.dump();
    text.resize((text.size() + 3) / 4 * 4, ' ');
    b.resize((b.size() + 3) / 4 * 4, 0);
    std::vector<unsigned char> out;
    auto u32 = [&](uint32_t v) {
      for (int i = 0; i < 4; ++i) out.push_back((v >> (8 * i)) & 0xff);
    };
    out.insert(out.end(), {'g', 'l', 'T', 'F'});
    u32(2);
    u32(uint32_t(12 + 8 + text.size() + 8 + b.size()));
    u32(uint32_t(text.size()));
    out.insert(out.end(), {'J', 'S', 'O', 'N'});
    out.insert(out.end(), text.begin(), text.end());
    u32(uint32_t(b.size()));
    out.insert(out.end(), {'B', 'I', 'N', 0});
    out.insert(out.end(), b.begin(), b.end());
    std::ofstream(path, std::ios::binary).write(reinterpret_cast<const char*>(out.data()), std::streamsize(out.size()));
    return path.string();
  }
};

// glTF material JSON: base colour factor, alpha mode, double-sided, unlit.
inline json mat(glm::vec4 color, const char* alpha_mode = "OPAQUE", bool double_sided = false, bool unlit = true) {
  json m = {{"pbrMetallicRoughness", {{"baseColorFactor", {color.r, color.g, color.b, color.a}}}},
            {"alphaMode", alpha_mode},
            {"doubleSided", double_sided}};
  if (unlit) m["extensions"] = {{"KHR_materials_unlit", json::object()}};
  return m;
}

// Rotation quaternion (x, y, z, w) of `deg` degrees about +Y.
inline glm::dvec4 about_y(double deg) {
  const double h = glm::radians(deg) / 2;
  return {0, std::sin(h), 0, std::cos(h)};
}

}  // namespace mattest
