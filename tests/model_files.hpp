// Writers of model files for the tests and tools/write_model: a Scene written out as PLY (ASCII or
// binary), OBJ (+ MTL) or binary STL, so that the readers can be checked against the scene they
// came from and big models can be generated rather than shipped.
//
// All three bake each object's transform into its vertices (computed in double, then rounded to
// float: what a reader of the file gets; a mirroring transform's triangles turned to keep their
// front faces), as none of the formats has a node tree. OBJ keeps one `o` group per object, in
// object order, with a material per scene material (Kd = base colour, d = its alpha; a mesh
// without material, or with a per-object colour, gets none, so it reads back with the per-object
// colour); PLY and STL are one mesh. Normals are written where every mesh has its own (no mesh is
// flat), else none (the file reads back flat). PLY vertex colours (optional, and only where every
// mesh has a material of its own colour) are the base colours of the materials as bytes. Throws std::runtime_error when a file cannot be written.
#pragma once
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/scene/scene.hpp"

namespace occtest {

struct WorldVertex {
  glm::vec3 p, n;
};

// An object's mesh space to world: positions by its transform, normals by the inverse transpose.
struct ToWorld {
  explicit ToWorld(const occ::Object& o)
      : t(o.transform), normal(glm::transpose(glm::inverse(glm::dmat3(o.transform)))) {}
  WorldVertex operator()(const occ::Mesh& m, uint32_t v) const {
    const glm::dvec3 p = glm::dvec3(t * glm::dvec4(glm::dvec3(m.positions[v]), 1.0));
    const glm::dvec3 n = normal * glm::dvec3(m.normals[v]);
    return {glm::vec3(p), glm::vec3(glm::length(n) > 0 ? glm::normalize(n) : n)};
  }
  // The object's corner k of a triangle whose corners are c: mirrored objects' corners 1 and 2
  // swapped (the front face kept).
  uint32_t corner(const uint32_t* c, int k) const { return mirrored && k ? c[3 - k] : c[k]; }
  glm::dmat4 t;
  glm::dmat3 normal;
  bool mirrored = glm::determinant(glm::dmat3(t)) < 0;
};

// Whether every object's mesh has a material with its own colour (not kNoMaterial, not the
// per-object colour).
inline bool every_mesh_has_its_colour(const occ::Scene& s) {
  for (const occ::Object& o : s.objects) {
    const occ::Material* m = s.material_of(o.mesh);
    if (!m || m->object_color) return false;
  }
  return true;
}

inline bool every_mesh_has_normals(const occ::Scene& s) {
  for (const occ::Mesh& m : s.meshes)
    if (m.flat) return false;
  return true;
}

// The scene as the writers write it: every object's vertices and normals baked as above, each
// object with a mesh of its own and the identity transform, materials kept; one_mesh: every
// object's triangles in one mesh of one object, without material (a PLY or STL without colours as
// its reader gets it). Written as glTF (save_gltf), it is what a model file of `s` renders to the
// pixel: the frames of `s` itself differ where its transforms round otherwise (a baked vertex or
// normal is rounded to float once, the renderer's float model-view matrix times the mesh's float
// vertex is not) and, for one_mesh, where coincident faces of two objects are drawn in another
// order (one mesh draws in cluster order, objects front to back).
inline occ::Scene baked(const occ::Scene& s, bool one_mesh) {
  occ::Scene b;
  b.source = s.source + " (baked)";
  if (!one_mesh) b.materials = s.materials;
  for (const occ::Object& o : s.objects) {
    const occ::Mesh& m = s.meshes[o.mesh];
    if (!one_mesh || b.meshes.empty()) {
      b.meshes.emplace_back();
      b.meshes.back().name = one_mesh ? "baked" : m.name;
      b.meshes.back().material = one_mesh ? occ::kNoMaterial : m.material;
      b.meshes.back().flat = m.flat;
      b.objects.push_back({uint32_t(b.meshes.size() - 1), glm::dmat4(1.0), one_mesh ? "baked" : o.name});
    }
    occ::Mesh& out = b.meshes.back();
    out.flat = out.flat || m.flat;
    const ToWorld world(o);
    const uint32_t base = uint32_t(out.positions.size());
    for (uint32_t v = 0; v < m.positions.size(); ++v) {
      const WorldVertex w = world(m, v);
      out.positions.push_back(w.p);
      out.normals.push_back(w.n);
    }
    for (size_t t = 0; t + 2 < m.indices.size(); t += 3)
      for (int k = 0; k < 3; ++k) out.indices.push_back(base + world.corner(&m.indices[t], k));
  }
  return b;
}

class File {
 public:
  File(const std::string& path, const char* mode) : f_(std::fopen(path.c_str(), mode)), path_(path) {
    if (!f_) throw std::runtime_error("cannot write " + path);
  }
  ~File() {
    if (f_) std::fclose(f_);
  }
  std::FILE* get() const { return f_; }
  void close() {
    const bool ok = !std::ferror(f_) && std::fclose(f_) == 0;
    f_ = nullptr;
    if (!ok) throw std::runtime_error("cannot write " + path_ + " (disk full?)");
  }

 private:
  std::FILE* f_;
  std::string path_;
};

inline void write_ply(const occ::Scene& s, const std::string& path, bool binary, bool colours) {
  const bool normals = every_mesh_has_normals(s);
  colours = colours && every_mesh_has_its_colour(s);
  uint64_t nv = 0, nf = 0;
  for (const occ::Object& o : s.objects) {
    nv += s.meshes[o.mesh].positions.size();
    nf += s.meshes[o.mesh].indices.size() / 3;
  }
  File f(path, "wb");
  std::fprintf(f.get(), "ply\nformat %s 1.0\ncomment occswitch tests/model_files.hpp\nelement vertex %llu\n",
               binary ? "binary_little_endian" : "ascii", static_cast<unsigned long long>(nv));
  std::fprintf(f.get(), "property float x\nproperty float y\nproperty float z\n");
  if (normals) std::fprintf(f.get(), "property float nx\nproperty float ny\nproperty float nz\n");
  if (colours) std::fprintf(f.get(), "property uchar red\nproperty uchar green\nproperty uchar blue\n");
  std::fprintf(f.get(), "element face %llu\nproperty list uchar int vertex_indices\nend_header\n",
               static_cast<unsigned long long>(nf));
  std::vector<uint8_t> row;
  for (const occ::Object& o : s.objects) {
    const occ::Mesh& m = s.meshes[o.mesh];
    const occ::Material* mat = s.material_of(o.mesh);
    const glm::vec4 c = mat ? mat->base_color : glm::vec4(1.0f);
    uint8_t rgb[3];
    for (int k = 0; k < 3; ++k) rgb[k] = uint8_t(std::lround(std::clamp(c[k], 0.0f, 1.0f) * 255.0f));
    const ToWorld world(o);
    for (uint32_t v = 0; v < m.positions.size(); ++v) {
      const WorldVertex w = world(m, v);
      if (binary) {
        row.clear();
        auto put = [&](const void* p, size_t n) { row.insert(row.end(), (const uint8_t*)p, (const uint8_t*)p + n); };
        put(&w.p, 12);
        if (normals) put(&w.n, 12);
        if (colours) put(rgb, 3);
        std::fwrite(row.data(), 1, row.size(), f.get());
      } else {
        std::fprintf(f.get(), "%.9g %.9g %.9g", w.p.x, w.p.y, w.p.z);
        if (normals) std::fprintf(f.get(), " %.9g %.9g %.9g", w.n.x, w.n.y, w.n.z);
        if (colours) std::fprintf(f.get(), " %d %d %d", rgb[0], rgb[1], rgb[2]);
        std::fputc('\n', f.get());
      }
    }
  }
  uint32_t base = 0;
  for (const occ::Object& o : s.objects) {
    const occ::Mesh& m = s.meshes[o.mesh];
    const ToWorld world(o);
    for (size_t t = 0; t + 2 < m.indices.size(); t += 3) {
      const uint32_t* c = &m.indices[t];
      const int32_t idx[3] = {int32_t(base + world.corner(c, 0)), int32_t(base + world.corner(c, 1)),
                              int32_t(base + world.corner(c, 2))};
      if (binary) {
        const uint8_t three = 3;
        std::fwrite(&three, 1, 1, f.get());
        std::fwrite(idx, 4, 3, f.get());
      } else {
        std::fprintf(f.get(), "3 %d %d %d\n", idx[0], idx[1], idx[2]);
      }
    }
    base += uint32_t(m.positions.size());
  }
  f.close();
}

// path (.obj) and its MTL beside it (path with .mtl); materials false: no `usemtl` (every object
// reads back in its per-object colour, double-sided).
inline void write_obj(const occ::Scene& s, const std::string& path, bool materials = true) {
  const bool normals = every_mesh_has_normals(s);
  const std::string mtl = path.substr(0, path.rfind('.')) + ".mtl";
  {
    File m(mtl, "w");
    for (size_t k = 0; k < s.materials.size(); ++k) {
      const glm::vec4 c = s.materials[k].base_color;
      std::fprintf(m.get(), "newmtl m%zu\nKd %.9g %.9g %.9g\nd %.9g\n", k, c.r, c.g, c.b, c.a);
    }
    m.close();
  }
  File f(path, "w");
  std::fprintf(f.get(), "# occswitch tests/model_files.hpp\nmtllib %s\n", mtl.substr(mtl.rfind('/') + 1).c_str());
  uint64_t base = 1;
  for (size_t oi = 0; oi < s.objects.size(); ++oi) {
    const occ::Object& o = s.objects[oi];
    const occ::Mesh& m = s.meshes[o.mesh];
    std::fprintf(f.get(), "o object%zu\n", oi);
    const occ::Material* mat = s.material_of(o.mesh);
    if (materials && mat && !mat->object_color) std::fprintf(f.get(), "usemtl m%u\n", m.material);
    const ToWorld world(o);
    for (uint32_t v = 0; v < m.positions.size(); ++v) {
      const WorldVertex w = world(m, v);
      std::fprintf(f.get(), "v %.9g %.9g %.9g\n", w.p.x, w.p.y, w.p.z);
      if (normals) std::fprintf(f.get(), "vn %.9g %.9g %.9g\n", w.n.x, w.n.y, w.n.z);
    }
    for (size_t t = 0; t + 2 < m.indices.size(); t += 3) {
      const uint32_t* k = &m.indices[t];
      const uint64_t a = base + world.corner(k, 0), b = base + world.corner(k, 1), c = base + world.corner(k, 2);
      if (normals)
        std::fprintf(f.get(), "f %llu//%llu %llu//%llu %llu//%llu\n", (unsigned long long)a, (unsigned long long)a,
                     (unsigned long long)b, (unsigned long long)b, (unsigned long long)c, (unsigned long long)c);
      else
        std::fprintf(f.get(), "f %llu %llu %llu\n", (unsigned long long)a, (unsigned long long)b, (unsigned long long)c);
    }
    base += m.positions.size();
  }
  f.close();
}

inline void write_stl(const occ::Scene& s, const std::string& path) {
  uint32_t n = 0;
  for (const occ::Object& o : s.objects) n += uint32_t(s.meshes[o.mesh].indices.size() / 3);
  File f(path, "wb");
  char header[80] = "occswitch tests/model_files.hpp";
  std::fwrite(header, 1, 80, f.get());
  std::fwrite(&n, 4, 1, f.get());
  for (const occ::Object& o : s.objects) {
    const occ::Mesh& m = s.meshes[o.mesh];
    const ToWorld world(o);
    for (size_t t = 0; t + 2 < m.indices.size(); t += 3) {
      glm::vec3 p[3];
      for (int k = 0; k < 3; ++k) p[k] = world(m, world.corner(&m.indices[t], k)).p;
      const glm::vec3 c = glm::cross(p[1] - p[0], p[2] - p[0]);
      const glm::vec3 nrm = glm::length(c) > 0 ? glm::normalize(c) : glm::vec3(0);
      std::fwrite(&nrm, 4, 3, f.get());
      std::fwrite(p, 4, 9, f.get());
      const uint16_t attr = 0;
      std::fwrite(&attr, 2, 1, f.get());
    }
  }
  f.close();
}

// `in` (any file Assimp reads: DAE, glTF, OBJ, ...) written as ASCII FBX 7.5 at `out` by Assimp's
// own exporter (`assimp export IN OUT -ffbxa`, Debian assimp-utils: scripts/setup.sh), so that FBX
// is tested without shipping one. ASCII, as Assimp 5.2 refuses its own binary FBX ("FBX-Tokenize
// (offset 0x1ef) block offset is out of range"). Whether it wrote `out` (false without assimp).
inline bool assimp_export_fbx(const std::string& in, const std::string& out) {
  const std::string cmd = "assimp export '" + in + "' '" + out + "' -ffbxa >'" + out + ".log' 2>&1";
  if (std::system(cmd.c_str()) != 0) return false;
  std::FILE* f = std::fopen(out.c_str(), "rb");
  if (f) std::fclose(f);
  return f != nullptr;
}

}  // namespace occtest
