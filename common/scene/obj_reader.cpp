// OBJ through tinyobjloader (obj_reader.hpp): its shapes, faces and materials checked and turned
// into meshes, each corner's (position, normal, texture coordinate) triple one vertex.
#include "common/scene/obj_reader.hpp"

#include <stb/stb_image.h>
#include <tiny_obj_loader.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <unordered_map>

#include "common/error.hpp"
#include "common/hash.hpp"
#include "common/scene/model_mesh.hpp"

namespace occ {
namespace {

// tinyobjloader's MTL reader, recording each MTL file it is asked for (as it was just before).
class RecordingMtl : public tinyobj::MaterialReader {
 public:
  RecordingMtl(std::string dir, std::vector<SourceFile>* files) : dir_(std::move(dir)), reader_(dir_), files_(files) {}
  bool operator()(const std::string& id, std::vector<tinyobj::material_t>* m, std::map<std::string, int>* map,
                  std::string* warn, std::string* err) override {
    if (auto f = source_file(dir_ + id)) files_->push_back(*f);
    return reader_(id, m, map, warn, err);
  }

 private:
  std::string dir_;
  tinyobj::MaterialFileReader reader_;
  std::vector<SourceFile>* files_;
};

std::string one_line(std::string s) {
  while (!s.empty() && (s.back() == '\n' || s.back() == ' ')) s.pop_back();
  for (size_t p; (p = s.find('\n')) != std::string::npos;) s.replace(p, 1, "; ");
  return s;
}

struct CornerHash {
  size_t operator()(const std::array<int, 3>& k) const {
    return size_t(mix64((uint64_t(uint32_t(k[0])) << 32 | uint32_t(k[1])) ^ mix64(uint32_t(k[2]))));
  }
};

class ObjReader {
 public:
  ObjReader(const std::string& file, const tinyobj::attrib_t& a, std::vector<tinyobj::material_t> mats)
      : file_(file), a_(a), mats_(std::move(mats)) {}

  void read(const std::vector<tinyobj::shape_t>& shapes) {
    for (size_t si = 0; si < shapes.size(); ++si) {
      const tinyobj::shape_t& sh = shapes[si];
      const std::string name = sh.name.empty() ? "shape " + std::to_string(si) : sh.name;
      skipped_ += sh.lines.num_line_vertices.size() + sh.points.indices.size();
      // The shape's faces by material, in the order the materials first appear.
      std::vector<int> order;
      std::map<int, std::vector<size_t>> faces;
      const tinyobj::mesh_t& m = sh.mesh;
      if (m.material_ids.size() != m.num_face_vertices.size()) fail(name, "material ids do not match the faces");
      std::vector<size_t> first(m.num_face_vertices.size());
      size_t at = 0;
      for (size_t f = 0; f < m.num_face_vertices.size(); ++f) {
        first[f] = at;
        const unsigned n = m.num_face_vertices[f];
        if (n < 3) fail(name, "face " + std::to_string(f) + " has " + std::to_string(n) +
                                  " vertices (a line cut short: truncated file?)");
        at += n;
        auto [it, fresh] = faces.try_emplace(m.material_ids[f]);
        if (fresh) order.push_back(m.material_ids[f]);
        it->second.push_back(f);
      }
      if (at != m.indices.size()) fail(name, "face sizes do not match the indices");
      for (int mat : order) add_mesh(name, m, first, faces[mat], mat);
    }
    if (skipped_ > 0) std::cerr << file_ << ": skipped " << skipped_ << " lines and points\n";
    if (scene_.objects.empty()) throw InputError(file_ + ": no triangles to draw");
  }

  Scene scene_;

 private:
  [[noreturn]] void fail(const std::string& where, const std::string& what) const {
    throw InputError(file_ + ": " + where + ": " + what);
  }

  void add_mesh(const std::string& name, const tinyobj::mesh_t& sm, const std::vector<size_t>& first,
                const std::vector<size_t>& faces, int mat) {
    Mesh m;
    m.name = name;
    m.material = material(mat, name);
    const bool textured = m.material != kNoMaterial && scene_.materials[m.material].base_color_texture >= 0;
    bool normals = true;
    std::unordered_map<std::array<int, 3>, uint32_t, CornerHash> vertex_of;
    auto vertex = [&](const tinyobj::index_t& c) {
      const size_t nv = a_.vertices.size() / 3, nn = a_.normals.size() / 3, nt = a_.texcoords.size() / 2;
      if (c.vertex_index < 0 || size_t(c.vertex_index) >= nv)
        fail(name, "vertex index " + std::to_string(c.vertex_index + 1) + " out of range (" + std::to_string(nv) + ")");
      if (c.normal_index >= 0 && size_t(c.normal_index) >= nn) fail(name, "normal index out of range");
      if (c.texcoord_index >= 0 && size_t(c.texcoord_index) >= nt) fail(name, "texture coordinate index out of range");
      normals &= c.normal_index >= 0;
      const std::array<int, 3> key = {c.vertex_index, c.normal_index, textured ? c.texcoord_index : -1};
      const auto [it, fresh] = vertex_of.try_emplace(key, uint32_t(m.positions.size()));
      if (!fresh) return it->second;
      const float* p = &a_.vertices[3 * size_t(c.vertex_index)];
      m.positions.push_back({p[0], p[1], p[2]});
      if (c.normal_index >= 0) {
        const float* n = &a_.normals[3 * size_t(c.normal_index)];
        m.normals.push_back({n[0], n[1], n[2]});
      } else {
        m.normals.push_back(glm::vec3(0.0f));
      }
      if (textured) {
        if (c.texcoord_index < 0) fail(name, "a textured material's face without texture coordinates");
        const float* t = &a_.texcoords[2 * size_t(c.texcoord_index)];
        m.uvs.push_back({t[0], 1.0f - t[1]});
      }
      return it->second;
    };
    for (size_t f : faces) {
      const uint32_t v0 = vertex(sm.indices[first[f]]);
      for (unsigned k = 1; k + 1 < sm.num_face_vertices[f]; ++k)
        m.indices.insert(m.indices.end(), {v0, vertex(sm.indices[first[f] + k]), vertex(sm.indices[first[f] + k + 1])});
    }
    for (const glm::vec3& p : m.positions)
      if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) fail(name, "a vertex is not finite");
    for (glm::vec3& n : m.normals)
      if (!std::isfinite(n.x) || !std::isfinite(n.y) || !std::isfinite(n.z)) n = glm::vec3(0.0f);
    const ModelMeshCounts c = add_model_mesh(scene_, std::move(m), normals);
    scene_.zero_area_triangles += c.zero_area;
    scene_.repeated_triangles += c.repeated;
    for (uint32_t k : c.meshes) scene_.objects.push_back(Object{k, glm::dmat4(1.0), name});
  }

  uint32_t material(int index, const std::string& where) {
    if (index < 0) return kNoMaterial;
    if (size_t(index) >= mats_.size()) fail(where, "material " + std::to_string(index) + " out of range");
    if (const auto it = materials_.find(index); it != materials_.end()) return it->second;
    const tinyobj::material_t& om = mats_[size_t(index)];
    Material m;
    m.name = om.name;
    m.base_color = {om.diffuse[0], om.diffuse[1], om.diffuse[2], om.dissolve};
    for (int k = 0; k < 4; ++k)
      if (!(m.base_color[k] >= 0.0f && m.base_color[k] <= 1.0f))
        fail("material '" + om.name + "'", "Kd and d must be numbers in [0, 1]");
    if (m.base_color.a < 1.0f) m.alpha_mode = AlphaMode::Blend;
    if (!om.diffuse_texname.empty()) {
      std::string rel = om.diffuse_texname;
      std::replace(rel.begin(), rel.end(), '\\', '/');
      const std::string p = (std::filesystem::path(file_).parent_path() / rel).string();
      if (auto sf = source_file(p)) scene_.files.push_back(*sf);
      int w = 0, h = 0, ch = 0;
      stbi_uc* px = stbi_load(p.c_str(), &w, &h, &ch, 4);
      if (!px) fail("material '" + om.name + "'", "cannot load texture '" + p + "': " + stbi_failure_reason());
      Image img;
      img.width = w;
      img.height = h;
      img.rgba.assign(px, px + size_t(w) * size_t(h) * 4);
      stbi_image_free(px);
      scene_.images.push_back(std::move(img));
      scene_.textures.push_back(Texture{uint32_t(scene_.images.size() - 1), {}});
      m.base_color_texture = int32_t(scene_.textures.size() - 1);
    }
    scene_.materials.push_back(std::move(m));
    return materials_[index] = uint32_t(scene_.materials.size() - 1);
  }

  const std::string& file_;
  const tinyobj::attrib_t& a_;
  std::vector<tinyobj::material_t> mats_;
  std::map<int, uint32_t> materials_;  // OBJ material -> ours
  size_t skipped_ = 0;
};

}  // namespace

Scene load_obj(const std::string& path) {
  std::vector<SourceFile> files;
  if (auto f = source_file(path)) files.push_back(*f);
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path + ": cannot open file");
  std::string dir = std::filesystem::path(path).parent_path().string();
  if (!dir.empty()) dir += "/";
  RecordingMtl mtl(dir, &files);
  tinyobj::attrib_t attrib;
  std::vector<tinyobj::shape_t> shapes;
  std::vector<tinyobj::material_t> materials;
  std::string warn, err;
  bool ok = false;
  try {  // third-party code: anything it throws is still bad input
    ok = tinyobj::LoadObj(&attrib, &shapes, &materials, &warn, &err, &in, &mtl, true, false);
  } catch (const std::exception& e) {
    err += e.what();
  }
  if (!ok || !err.empty()) throw InputError(path + ": invalid OBJ: " + one_line(err.empty() ? "parse failed" : err));
  // tinyobjloader drops a face of fewer than three vertices with a warning: a line cut short (a
  // truncated file) or a broken one, never a scene without it.
  if (warn.find("Degenerated face") != std::string::npos)
    throw InputError(path + ": a face of fewer than three vertices (a line cut short: truncated file?): " +
                     one_line(warn));
  if (!warn.empty()) std::cerr << path << ": warning: " << one_line(warn) << "\n";
  ObjReader r(path, attrib, std::move(materials));
  r.read(shapes);
  Scene s = std::move(r.scene_);
  files.insert(files.end(), s.files.begin(), s.files.end());
  s.files = std::move(files);
  s.source = path;
  return s;
}

}  // namespace occ
