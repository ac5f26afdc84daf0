// glTF 2.0 via tinygltf with full validation (gltf_reader.hpp): every index and byte range is
// checked before use.
#include "common/scene/gltf_reader.hpp"

#include <stb/stb_image.h>
#include <tiny_gltf.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <climits>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>
#include <glm/gtc/type_ptr.hpp>
#include <iostream>
#include <map>
#include <memory>
#include <numeric>
#include <string_view>

#include "common/error.hpp"

namespace occ {
namespace {

std::string num(size_t v) { return std::to_string(v); }

// tinygltf's multi-line messages as one line.
std::string one_line(std::string s) {
  while (!s.empty() && (s.back() == '\n' || s.back() == ' ')) s.pop_back();
  for (size_t p; (p = s.find('\n')) != std::string::npos;) s.replace(p, 1, "; ");
  return s;
}

std::vector<unsigned char> read_file(const std::string& path) {
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) throw InputError(path + ": cannot open file: " + std::strerror(errno));
  std::vector<unsigned char> data;
  unsigned char chunk[1 << 16];
  size_t n;
  while ((n = std::fread(chunk, 1, sizeof chunk, f)) > 0) data.insert(data.end(), chunk, chunk + n);
  bool failed = std::ferror(f);
  int err = errno;
  std::fclose(f);
  if (failed) throw InputError(path + ": cannot read file: " + std::strerror(err));
  return data;
}

// tinygltf's file reader, recording each file it reads (its buffers' and images' uris) in the
// std::vector<SourceFile> behind user_data, as it was just before it was read.
bool read_and_record(std::vector<unsigned char>* out, std::string* err, const std::string& path, void* user_data) {
  if (auto f = source_file(path)) static_cast<std::vector<SourceFile>*>(user_data)->push_back(*f);
  return tinygltf::ReadWholeFile(out, err, path, nullptr);
}

// Images are decoded later, and only those a drawn material uses (GltfReader::image). Here the
// encoded bytes of uri images (files, data URIs) are kept; bytes of buffer-view images are not
// touched (tinygltf passes them unchecked: GltfReader reads them through its checked views).
bool keep_image_bytes(tinygltf::Image* image, const int, std::string*, std::string*, int, int,
                      const unsigned char* bytes, int size, void*) {
  if (image->bufferView == -1 && bytes && size > 0) image->image.assign(bytes, bytes + size);
  return true;
}

// Does [offset, offset + (count-1) * stride + elem) fit in size bytes? Overflow-safe; stride >= elem
// (a stride of 0 only with elem 0: every element is the same empty range).
bool fits(size_t offset, size_t count, size_t stride, size_t elem, size_t size) {
  if (count == 0) return offset <= size;
  if (offset > size || elem > size - offset) return false;
  return stride == 0 || count - 1 <= (size - offset - elem) / stride;
}

// count elements, stride bytes apart, all inside their buffer.
struct Strided {
  const unsigned char* data;
  size_t count, stride;
  const unsigned char* operator[](size_t i) const { return data + i * stride; }
};

// Turns a parsed tinygltf model into a Scene. Every index and byte range is checked before use;
// failures throw InputError "<file>: <where>: <what>".
class GltfReader {
 public:
  GltfReader(const tinygltf::Model& model, std::string file) : m_(model), file_(std::move(file)) {}

  Scene read() {
    check_node_forest();
    std::vector<std::pair<int, glm::dmat4>> stack;  // (node, parent's world transform)
    const std::vector<int> roots = root_nodes();
    for (auto r = roots.rbegin(); r != roots.rend(); ++r) stack.emplace_back(*r, glm::dmat4(1.0));
    while (!stack.empty()) {  // depth-first, children in file order
      auto [n, parent] = stack.back();
      stack.pop_back();
      const tinygltf::Node& node = m_.nodes[n];
      const glm::dmat4 world = parent * local_transform(node, n);
      if (node.mesh != -1) add_objects(node, n, world);
      for (auto c = node.children.rbegin(); c != node.children.rend(); ++c) stack.emplace_back(*c, world);
    }
    if (skipped_ > 0)
      std::cerr << file_ << ": skipped " << skipped_ << " non-triangle primitives (lines/points)\n";
    return std::move(scene_);
  }

 private:
  [[noreturn]] void fail(const std::string& where, const std::string& what) const {
    throw InputError(file_ + ": " + where + ": " + what);
  }

  template <class T>
  const T& at(const std::vector<T>& v, int i, const char* kind, const char* plural,
              const std::string& where) const {
    if (i < 0 || size_t(i) >= v.size())
      fail(where, std::string(kind) + " " + std::to_string(i) + " out of range (" + num(v.size()) + " " +
                      plural + ")");
    return v[size_t(i)];
  }

  // glTF requires disjoint strict trees: at most one parent per node, no cycles. Fills parent_.
  void check_node_forest() {
    parent_.assign(m_.nodes.size(), -1);
    for (size_t n = 0; n < m_.nodes.size(); ++n)
      for (int c : m_.nodes[n].children) {
        at(m_.nodes, c, "child node", "nodes", "node " + num(n));
        if (parent_[size_t(c)] != -1)
          fail("node " + num(size_t(c)),
               "has two parents (nodes " + num(size_t(parent_[size_t(c)])) + " and " + num(n) + ")");
        parent_[size_t(c)] = int(n);
      }
    // With single parents, a node is in a cycle iff walking up never reaches a root.
    std::vector<uint8_t> state(m_.nodes.size(), 0);  // 0 unseen, 1 on the current walk, 2 reaches a root
    for (size_t n = 0; n < m_.nodes.size(); ++n) {
      std::vector<int> walk;
      int j = int(n);
      for (; j != -1 && state[size_t(j)] == 0; j = parent_[size_t(j)]) {
        state[size_t(j)] = 1;
        walk.push_back(j);
      }
      if (j != -1 && state[size_t(j)] == 1) fail("node " + num(size_t(j)), "the node hierarchy has a cycle");
      for (int w : walk) state[size_t(w)] = 2;
    }
  }

  // Roots of the default scene, else of scene 0, else every parentless node.
  std::vector<int> root_nodes() const {
    if (m_.scenes.empty() && m_.defaultScene == -1) {
      std::vector<int> roots;
      for (size_t n = 0; n < m_.nodes.size(); ++n)
        if (parent_[n] == -1) roots.push_back(int(n));
      return roots;
    }
    const int s = m_.defaultScene != -1 ? m_.defaultScene : 0;
    const tinygltf::Scene& scene = at(m_.scenes, s, "scene", "scenes", "default scene");
    const std::string where = "scene " + std::to_string(s);
    for (int r : scene.nodes) {
      at(m_.nodes, r, "node", "nodes", where);
      if (parent_[size_t(r)] != -1)
        fail(where,
             "root node " + std::to_string(r) + " is a child of node " + num(size_t(parent_[size_t(r)])));
    }
    return scene.nodes;
  }

  // matrix, or translation * rotation * scale (glTF column-major, quaternion x y z w).
  glm::dmat4 local_transform(const tinygltf::Node& node, int n) const {
    const std::string where = "node " + std::to_string(n);
    auto check_size = [&](const std::vector<double>& v, size_t size, const char* what) {
      if (!v.empty() && v.size() != size)
        fail(where, std::string(what) + " must have " + num(size) + " numbers");
    };
    check_size(node.matrix, 16, "matrix");
    check_size(node.translation, 3, "translation");
    check_size(node.rotation, 4, "rotation");
    check_size(node.scale, 3, "scale");
    glm::dmat4 local(1.0);
    if (!node.matrix.empty()) {
      local = glm::make_mat4(node.matrix.data());
    } else {
      if (!node.translation.empty()) local = glm::translate(local, glm::make_vec3(node.translation.data()));
      if (!node.rotation.empty()) {
        const auto& r = node.rotation;
        local *= glm::mat4_cast(glm::normalize(glm::dquat(r[3], r[0], r[1], r[2])));
      }
      if (!node.scale.empty()) local = glm::scale(local, glm::make_vec3(node.scale.data()));
    }
    for (int c = 0; c < 4; ++c)
      for (int r = 0; r < 4; ++r)
        if (!std::isfinite(local[c][r])) fail(where, "transform is not finite");
    return local;
  }

  void add_objects(const tinygltf::Node& node, int n, const glm::dmat4& world) {
    const std::string where = "node " + std::to_string(n);
    for (int c = 0; c < 4; ++c)
      for (int r = 0; r < 4; ++r)
        if (!std::isfinite(world[c][r])) fail(where, "world transform is not finite");
    at(m_.meshes, node.mesh, "mesh", "meshes", where);
    auto [it, fresh] = mesh_cache_.try_emplace(node.mesh);
    if (fresh) {
      const tinygltf::Mesh& mesh = m_.meshes[size_t(node.mesh)];
      for (size_t p = 0; p < mesh.primitives.size(); ++p) it->second.push_back(build_mesh(node.mesh, int(p)));
    }
    const std::string name = node.name.empty() ? where : node.name;
    scene_.zero_area_triangles += zero_area_of_mesh_[node.mesh];  // counted per instance, as drawn
    scene_.repeated_triangles += repeated_of_mesh_[node.mesh];
    for (int m : it->second)
      if (m >= 0) scene_.objects.push_back(Object{uint32_t(m), world, name});
  }

  const tinygltf::Accessor& accessor(int index, const std::string& where) const {
    return at(m_.accessors, index, "accessor", "accessors", where);
  }

  // The elements of accessor `index` (elem bytes each) after checking its views and bounds.
  Strided elements(int index, size_t elem, const std::string& where) const {
    const tinygltf::Accessor& a = accessor(index, where);
    const std::string an = "accessor " + std::to_string(index);
    if (a.sparse.isSparse) fail(where, an + ": sparse accessors are not supported");
    if (a.bufferView == -1) fail(where, an + " has no buffer view");
    const std::string bvn = "buffer view " + std::to_string(a.bufferView);
    const View view = buffer_view(a.bufferView, where, where + ": " + an, where + ": " + bvn);
    const tinygltf::BufferView& bv = view.bv;
    const size_t stride = bv.byteStride ? bv.byteStride : elem;
    if (stride < elem)
      fail(where, bvn + ": byteStride " + num(stride) + " is smaller than the element size " + num(elem));
    if (!fits(a.byteOffset, a.count, stride, elem, bv.byteLength))
      fail(where, an + " reads past the end of " + bvn);
    return {view.data + a.byteOffset, a.count, stride};
  }

  // A buffer view and its first byte, checked to lie inside its buffer. Errors name `where`;
  // view_where and buffer_where name the places that refer to the view and to its buffer.
  struct View {
    const tinygltf::BufferView& bv;
    const unsigned char* data;
  };
  View buffer_view(int index, const std::string& where, const std::string& view_where,
                   const std::string& buffer_where) const {
    const tinygltf::BufferView& bv = at(m_.bufferViews, index, "buffer view", "buffer views", view_where);
    const tinygltf::Buffer& buf = at(m_.buffers, bv.buffer, "buffer", "buffers", buffer_where);
    if (!fits(bv.byteOffset, 1, bv.byteLength, bv.byteLength, buf.data.size()))
      fail(where, "buffer view " + std::to_string(index) + " reads past the end of buffer " + std::to_string(bv.buffer));
    return {bv, buf.data.data() + bv.byteOffset};
  }

  // The scene index that `cache` holds for glTF index `index`, made by make() the first time.
  template <class Make>
  static uint32_t once(std::map<int, uint32_t>& cache, int index, const Make& make) {
    if (const auto it = cache.find(index); it != cache.end()) return it->second;
    const uint32_t made = make();
    cache.emplace(index, made);
    return made;
  }

  // A float VEC3 attribute with finite values.
  std::vector<glm::vec3> read_vec3(int index, const std::string& attr, const std::string& where) const {
    const tinygltf::Accessor& a = accessor(index, where);
    const std::string an = attr + " accessor " + std::to_string(index);
    if (a.type != TINYGLTF_TYPE_VEC3 || a.componentType != TINYGLTF_COMPONENT_TYPE_FLOAT || a.normalized)
      fail(where, an + " must be float VEC3");
    const Strided e = elements(index, sizeof(glm::vec3), where);
    std::vector<glm::vec3> out(e.count);
    for (size_t i = 0; i < e.count; ++i) {
      std::memcpy(&out[i], e[i], sizeof(glm::vec3));
      if (!std::isfinite(out[i].x) || !std::isfinite(out[i].y) || !std::isfinite(out[i].z))
        fail(where, an + ": element " + num(i) + " is not finite");
    }
    return out;
  }

  // An unsigned 8/16/32-bit SCALAR accessor.
  std::vector<uint32_t> read_indices(int index, const std::string& where) const {
    const tinygltf::Accessor& a = accessor(index, where);
    const int ct = a.componentType;
    const size_t size = ct == TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE    ? 1
                        : ct == TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT ? 2
                        : ct == TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT   ? 4
                                                                       : 0;
    if (a.type != TINYGLTF_TYPE_SCALAR || size == 0)
      fail(where, "index accessor " + std::to_string(index) + " must be an unsigned byte/short/int SCALAR");
    const Strided e = elements(index, size, where);
    std::vector<uint32_t> out(e.count);
    for (size_t i = 0; i < e.count; ++i) {  // little-endian host, like the float reads
      if (size == 1) {
        out[i] = *e[i];
      } else if (size == 2) {
        uint16_t v;
        std::memcpy(&v, e[i], 2);
        out[i] = v;
      } else {
        std::memcpy(&out[i], e[i], 4);
      }
    }
    return out;
  }

  // Mesh for primitive p of glTF mesh mi: its index in scene_.meshes, or -1 if it draws no
  // triangles (points/lines are counted in skipped_). Strips and fans become triangle lists.
  int build_mesh(int mi, int p) {
    const tinygltf::Mesh& gm = m_.meshes[size_t(mi)];
    const tinygltf::Primitive& prim = gm.primitives[size_t(p)];
    const std::string where = "mesh " + std::to_string(mi) + " primitive " + std::to_string(p);
    if (prim.mode >= TINYGLTF_MODE_POINTS && prim.mode <= TINYGLTF_MODE_LINE_STRIP) {
      ++skipped_;
      return -1;
    }
    if (prim.mode < TINYGLTF_MODE_TRIANGLES || prim.mode > TINYGLTF_MODE_TRIANGLE_FAN)
      fail(where, "mode " + std::to_string(prim.mode) + " is not a glTF primitive mode");
    const auto pos = prim.attributes.find("POSITION");
    if (pos == prim.attributes.end()) fail(where, "no POSITION attribute");

    Mesh mesh;
    mesh.name = (gm.name.empty() ? "mesh " + std::to_string(mi) : gm.name) +
                (gm.primitives.size() > 1 ? " primitive " + std::to_string(p) : "");
    mesh.positions = read_vec3(pos->second, "POSITION", where);
    const size_t vertices = mesh.positions.size();
    if (vertices > UINT32_MAX) fail(where, "more than 2^32 vertices");
    std::vector<uint32_t> v(prim.indices != -1 ? read_indices(prim.indices, where)
                                               : std::vector<uint32_t>(vertices));
    if (prim.indices == -1) std::iota(v.begin(), v.end(), 0u);
    for (uint32_t i : v)
      if (i >= vertices) fail(where, "index " + std::to_string(i) + " >= vertex count " + num(vertices));

    // Triangle lists per the glTF spec's strip/fan definitions (winding preserved).
    if (prim.mode == TINYGLTF_MODE_TRIANGLES) {
      if (v.size() % 3 != 0) fail(where, "index count " + num(v.size()) + " is not a multiple of 3");
      mesh.indices = std::move(v);
    } else {
      for (size_t i = 0; i + 2 < v.size(); ++i) {
        if (prim.mode == TINYGLTF_MODE_TRIANGLE_STRIP)
          mesh.indices.insert(mesh.indices.end(), {v[i], v[i + 1 + i % 2], v[i + 2 - i % 2]});
        else
          mesh.indices.insert(mesh.indices.end(), {v[i + 1], v[i + 2], v[0]});
      }
    }
    zero_area_of_mesh_[mi] += drop_zero_area_triangles(mesh);
    if (mesh.indices.empty()) return -1;

    mesh.material = material(prim.material, where);
    const Material& mat = scene_.materials[mesh.material];
    if (mat.base_color_texture >= 0) {
      const std::string attr = "TEXCOORD_" + std::to_string(texcoord_of_material_[mesh.material]);
      const auto uv = prim.attributes.find(attr);
      if (uv == prim.attributes.end())
        fail(where, "material " + std::to_string(prim.material) + " has a baseColorTexture but the primitive has no " +
                        attr);
      mesh.uvs = read_uvs(uv->second, attr, where);
      if (mesh.uvs.size() != vertices)
        fail(where, attr + " count " + num(mesh.uvs.size()) + " != POSITION count " + num(vertices));
    }
    if (const auto col = prim.attributes.find("COLOR_0"); col != prim.attributes.end()) {
      mesh.colors = read_colors(col->second, where);
      if (mesh.colors.size() != vertices)
        fail(where, "COLOR_0 count " + num(mesh.colors.size()) + " != POSITION count " + num(vertices));
    }
    const auto nrm = prim.attributes.find("NORMAL");
    const bool has_normals = nrm != prim.attributes.end();
    if (has_normals) {
      mesh.normals = read_vec3(nrm->second, "NORMAL", where);
      if (mesh.normals.size() != vertices)
        fail(where, "NORMAL count " + num(mesh.normals.size()) + " != POSITION count " + num(vertices));
    }
    // Before normals are computed: a face and its reversed copy on the same vertices would
    // cancel each other's normal there.
    if (mat.alpha_mode == AlphaMode::Opaque) repeated_of_mesh_[mi] += drop_repeated_triangles(mesh, mat.double_sided);
    if (has_normals) {
      repair_normals(mesh);
    } else {
      compute_normals(mesh);
      mesh.flat = true;
    }
    scene_.meshes.push_back(std::move(mesh));
    return int(scene_.meshes.size() - 1);
  }

  // Float, or normalized unsigned byte/short components (glTF's TEXCOORD_n and COLOR_0 types);
  // `components` per element. Returns count * components floats (normalized to [0, 1]).
  std::vector<float> read_normalized(int index, const std::string& an, int components, const std::string& where) const {
    const tinygltf::Accessor& a = accessor(index, where);
    const int ct = a.componentType;
    const size_t size = ct == TINYGLTF_COMPONENT_TYPE_FLOAT                          ? 4
                        : ct == TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE && a.normalized  ? 1
                        : ct == TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT && a.normalized ? 2
                                                                                       : 0;
    if (size == 0) fail(where, an + " must be float or normalized unsigned byte/short");
    const Strided e = elements(index, size * size_t(components), where);
    std::vector<float> out(e.count * size_t(components));
    for (size_t i = 0; i < e.count; ++i)
      for (int c = 0; c < components; ++c) {
        const unsigned char* p = e[i] + size * size_t(c);
        float v;
        if (size == 4) {
          std::memcpy(&v, p, 4);
          if (!std::isfinite(v)) fail(where, an + ": element " + num(i) + " is not finite");
        } else if (size == 2) {
          uint16_t u;
          std::memcpy(&u, p, 2);
          v = float(u) / 65535.0f;
        } else {
          v = float(*p) / 255.0f;
        }
        out[i * size_t(components) + size_t(c)] = v;
      }
    return out;
  }

  std::vector<glm::vec2> read_uvs(int index, const std::string& attr, const std::string& where) const {
    const std::string an = attr + " accessor " + std::to_string(index);
    if (accessor(index, where).type != TINYGLTF_TYPE_VEC2) fail(where, an + " must be VEC2");
    const std::vector<float> f = read_normalized(index, an, 2, where);
    std::vector<glm::vec2> out(f.size() / 2);
    for (size_t i = 0; i < out.size(); ++i) out[i] = {f[2 * i], f[2 * i + 1]};
    return out;
  }

  // COLOR_0 (VEC3 or VEC4) as RGBA8, components clamped to [0, 1].
  std::vector<uint32_t> read_colors(int index, const std::string& where) const {
    const std::string an = "COLOR_0 accessor " + std::to_string(index);
    const int type = accessor(index, where).type;
    if (type != TINYGLTF_TYPE_VEC3 && type != TINYGLTF_TYPE_VEC4) fail(where, an + " must be VEC3 or VEC4");
    const int n = type == TINYGLTF_TYPE_VEC3 ? 3 : 4;
    const std::vector<float> f = read_normalized(index, an, n, where);
    std::vector<uint32_t> out(f.size() / size_t(n));
    for (size_t i = 0; i < out.size(); ++i) {
      uint32_t rgba = 0;
      for (int c = 0; c < 4; ++c) {
        const float v = c < n ? std::clamp(f[i * size_t(n) + size_t(c)], 0.0f, 1.0f) : 1.0f;
        rgba |= uint32_t(std::lround(v * 255.0f)) << (8 * c);
      }
      out[i] = rgba;
    }
    return out;
  }

  // Scene material for glTF material `index` (-1: the glTF default material: single-sided, white
  // in glTF, drawn here in the per-object hashed colour like material-less generated scenes).
  uint32_t material(int index, const std::string& where) {
    return once(material_cache_, index, [&] { return new_material(index, where); });
  }
  uint32_t new_material(int index, const std::string& where) {
    Material m;
    int texcoord = 0;
    if (index == -1) {
      m.name = "glTF default material";
      m.object_color = true;
    } else {
      const tinygltf::Material& gm = at(m_.materials, index, "material", "materials", where);
      const std::string mw = "material " + std::to_string(index);
      m.name = gm.name.empty() ? mw : gm.name;
      // scene_export marks generated scenes' per-object colours this way.
      m.object_color = gm.extras.IsObject() && gm.extras.Has("occswitch_object_colour");
      const std::vector<double>& f = gm.pbrMetallicRoughness.baseColorFactor;
      if (f.size() != 4) fail(mw, "baseColorFactor must have 4 numbers");
      for (int c = 0; c < 4; ++c) {
        if (!(f[size_t(c)] >= 0.0 && f[size_t(c)] <= 1.0)) fail(mw, "baseColorFactor must be 4 numbers in [0, 1]");
        m.base_color[c] = float(f[size_t(c)]);
      }
      if (gm.alphaMode == "OPAQUE") m.alpha_mode = AlphaMode::Opaque;
      else if (gm.alphaMode == "MASK") m.alpha_mode = AlphaMode::Mask;
      else if (gm.alphaMode == "BLEND") m.alpha_mode = AlphaMode::Blend;
      else fail(mw, "alphaMode '" + gm.alphaMode + "' is not OPAQUE, MASK or BLEND");
      if (!(gm.alphaCutoff >= 0.0 && std::isfinite(gm.alphaCutoff))) fail(mw, "alphaCutoff must be a number >= 0");
      m.alpha_cutoff = float(gm.alphaCutoff);
      m.double_sided = gm.doubleSided;
      m.unlit = gm.extensions.count("KHR_materials_unlit") > 0;
      const tinygltf::TextureInfo& ti = gm.pbrMetallicRoughness.baseColorTexture;
      if (ti.index != -1) {
        if (ti.texCoord < 0) fail(mw, "baseColorTexture.texCoord must be >= 0");
        texcoord = ti.texCoord;
        m.base_color_texture = int32_t(texture(ti.index, mw + " baseColorTexture"));
      }
    }
    scene_.materials.push_back(std::move(m));
    texcoord_of_material_.push_back(texcoord);
    return uint32_t(scene_.materials.size() - 1);
  }

  uint32_t texture(int index, const std::string& where) {
    return once(texture_cache_, index, [&] { return new_texture(index, where); });
  }
  uint32_t new_texture(int index, const std::string& where) {
    const std::string tw = "texture " + std::to_string(index);
    const tinygltf::Texture& gt = at(m_.textures, index, "texture", "textures", where);
    if (gt.source == -1)
      fail(tw, "has no source image (image extensions such as KHR_texture_basisu are not supported)");
    Texture t;
    t.image = image(gt.source, tw);
    if (gt.sampler != -1) {
      const tinygltf::Sampler& gs = at(m_.samplers, gt.sampler, "sampler", "samplers", tw);
      const std::string sw = "sampler " + std::to_string(gt.sampler);
      auto check = [&](int v, std::initializer_list<int> allowed, const char* what) {
        if (v == -1 && std::string_view(what).find("wrap") == std::string_view::npos) return v;
        for (int a : allowed)
          if (v == a) return v;
        fail(sw, std::string(what) + " " + std::to_string(v) + " is not a glTF value");
      };
      t.sampler.mag_filter = check(gs.magFilter, {9728, 9729}, "magFilter");
      t.sampler.min_filter = check(gs.minFilter, {9728, 9729, 9984, 9985, 9986, 9987}, "minFilter");
      t.sampler.wrap_s = check(gs.wrapS, {33071, 33648, 10497}, "wrapS");
      t.sampler.wrap_t = check(gs.wrapT, {33071, 33648, 10497}, "wrapT");
    }
    scene_.textures.push_back(t);
    return uint32_t(scene_.textures.size() - 1);
  }

  // Decodes glTF image `index` (PNG, JPEG, ... through stb_image) to RGBA8.
  uint32_t image(int index, const std::string& where) {
    return once(image_cache_, index, [&] { return new_image(index, where); });
  }
  uint32_t new_image(int index, const std::string& where) {
    const tinygltf::Image& gi = at(m_.images, index, "image", "images", where);
    const std::string iw = "image " + std::to_string(index);
    // The encoded bytes: kept from a uri (keep_image_bytes), or those of its buffer view.
    const unsigned char* bytes = gi.image.data();
    size_t size = gi.image.size();
    if (gi.bufferView != -1) {
      const View view = buffer_view(gi.bufferView, iw, iw, iw);
      bytes = view.data;
      size = view.bv.byteLength;
    }
    if (size == 0)
      fail(iw, gi.uri.empty() ? std::string("has no data") : "cannot load '" + gi.uri + "' (missing or empty file)");
    if (size > size_t(INT_MAX)) fail(iw, "larger than 2 GiB");
    int w = 0, h = 0, channels = 0;
    std::unique_ptr<stbi_uc, void (*)(void*)> px(stbi_load_from_memory(bytes, int(size), &w, &h, &channels, 4),
                                                 stbi_image_free);
    if (!px) fail(iw, std::string("cannot decode") + (gi.uri.empty() ? "" : " '" + gi.uri + "'") + ": " +
                          stbi_failure_reason());
    Image img;
    img.width = w;
    img.height = h;
    img.rgba.assign(px.get(), px.get() + size_t(w) * size_t(h) * 4);
    scene_.images.push_back(std::move(img));
    return uint32_t(scene_.images.size() - 1);
  }

  const tinygltf::Model& m_;
  std::string file_;
  Scene scene_;
  std::map<int, uint64_t> zero_area_of_mesh_;  // glTF mesh -> zero-area triangles left out of its primitives
  std::map<int, uint64_t> repeated_of_mesh_;   // glTF mesh -> repeated triangles left out of them
  std::vector<int> parent_;                     // per node, -1 for roots
  std::map<int, std::vector<int>> mesh_cache_;  // glTF mesh -> scene mesh per primitive (-1: none)
  std::map<int, uint32_t> material_cache_;      // glTF material (-1: default) -> scene material
  std::vector<int> texcoord_of_material_;       // per scene material: its texture's TEXCOORD set
  std::map<int, uint32_t> texture_cache_;       // glTF texture -> scene texture
  std::map<int, uint32_t> image_cache_;         // glTF image -> scene image
  int skipped_ = 0;                             // non-triangle primitives of used meshes
};

bool ends_with_ci(const std::string& s, std::string_view suffix) {
  if (s.size() < suffix.size()) return false;
  for (size_t i = 0; i < suffix.size(); ++i)
    if (std::tolower(static_cast<unsigned char>(s[s.size() - suffix.size() + i])) != suffix[i]) return false;
  return true;
}

}  // namespace

Scene load_gltf(const std::string& path) {
  std::vector<SourceFile> files;
  if (auto f = source_file(path)) files.push_back(*f);
  const std::vector<unsigned char> bytes = read_file(path);
  if (bytes.size() > UINT_MAX) throw InputError(path + ": file larger than 4 GiB");
  // .glb / .gltf by extension, anything else by the binary magic.
  const bool binary = ends_with_ci(path, ".glb") || (!ends_with_ci(path, ".gltf") && bytes.size() >= 4 &&
                                                     std::memcmp(bytes.data(), "glTF", 4) == 0);
  tinygltf::TinyGLTF loader;
  loader.SetImageLoader(keep_image_bytes, nullptr);
  loader.SetFsCallbacks({tinygltf::FileExists, tinygltf::ExpandFilePath, read_and_record, tinygltf::WriteWholeFile, &files});
  tinygltf::Model model;
  std::string err, warn;
  const std::string base = std::filesystem::path(path).parent_path().string();
  bool ok = false;
  try {  // tinygltf is third-party code: anything it throws is still bad input
    ok = binary ? loader.LoadBinaryFromMemory(&model, &err, &warn, bytes.data(), unsigned(bytes.size()), base)
                : loader.LoadASCIIFromString(&model, &err, &warn, reinterpret_cast<const char*>(bytes.data()),
                                             unsigned(bytes.size()), base);
  } catch (const std::exception& e) {
    err += e.what();
  }
  if (!ok || !err.empty())
    throw InputError(path + ": invalid glTF: " + one_line(err.empty() ? "parse failed" : err) +
                     (warn.empty() ? "" : " (warnings: " + one_line(warn) + ")"));
  if (!warn.empty()) std::cerr << path << ": warning: " << one_line(warn) << "\n";
  Scene scene = GltfReader(model, path).read();
  scene.source = path;
  scene.files = std::move(files);
  return scene;
}

bool is_gltf_path(const std::string& path) { return ends_with_ci(path, ".gltf") || ends_with_ci(path, ".glb"); }

}  // namespace occ
