// Making scenes (contract in scene_io.hpp): glTF 2.0 via tinygltf with full validation, the
// procedural city, grid layouts, and the --scene spec parser.
#include "common/scene_io.hpp"

#include <stb/stb_image.h>
#include <tiny_gltf.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <charconv>
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
#include <tuple>

#include "common/city.hpp"
#include "common/cli.hpp"
#include "common/error.hpp"
#include "common/hash.hpp"
#include "common/plant.hpp"

namespace occ {
namespace {

// ------------------------------------------------------------------------------------- glTF

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

// Images are decoded later, and only those a drawn material uses (GltfReader::image). Here the
// encoded bytes of uri images (files, data URIs) are kept; bytes of buffer-view images are not
// touched (tinygltf passes them unchecked: GltfReader reads them through its checked views).
bool keep_image_bytes(tinygltf::Image* image, const int, std::string*, std::string*, int, int,
                      const unsigned char* bytes, int size, void*) {
  if (image->bufferView == -1 && bytes && size > 0) image->image.assign(bytes, bytes + size);
  return true;
}

// Does [offset, offset + (count-1) * stride + elem) fit in size bytes? Overflow-safe; stride >= elem.
bool fits(size_t offset, size_t count, size_t stride, size_t elem, size_t size) {
  if (count == 0) return offset <= size;
  if (offset > size || elem > size - offset) return false;
  return count - 1 <= (size - offset - elem) / stride;
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
    const tinygltf::BufferView& bv =
        at(m_.bufferViews, a.bufferView, "buffer view", "buffer views", where + ": " + an);
    const std::string bvn = "buffer view " + std::to_string(a.bufferView);
    const tinygltf::Buffer& buf = at(m_.buffers, bv.buffer, "buffer", "buffers", where + ": " + bvn);
    if (!fits(bv.byteOffset, 1, bv.byteLength, bv.byteLength, buf.data.size()))
      fail(where, bvn + " reads past the end of buffer " + std::to_string(bv.buffer));
    const size_t stride = bv.byteStride ? bv.byteStride : elem;
    if (stride < elem)
      fail(where, bvn + ": byteStride " + num(stride) + " is smaller than the element size " + num(elem));
    if (!fits(a.byteOffset, a.count, stride, elem, bv.byteLength))
      fail(where, an + " reads past the end of " + bvn);
    return {buf.data.data() + bv.byteOffset + a.byteOffset, a.count, stride};
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
    if (mesh.indices.empty()) return -1;

    if (const auto nrm = prim.attributes.find("NORMAL"); nrm != prim.attributes.end()) {
      mesh.normals = read_vec3(nrm->second, "NORMAL", where);
      if (mesh.normals.size() != vertices)
        fail(where, "NORMAL count " + num(mesh.normals.size()) + " != POSITION count " + num(vertices));
      repair_normals(mesh);
    } else {
      compute_normals(mesh);
    }

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

  // Zero-length normals (a NORMAL attribute may have them) would shade as NaN: replace them by
  // the computed smooth normal of their vertex.
  static void repair_normals(Mesh& mesh) {
    bool bad = false;
    for (const glm::vec3& n : mesh.normals) bad |= !(glm::dot(n, n) > 1e-12f);
    if (!bad) return;
    Mesh computed;
    computed.positions = mesh.positions;
    computed.indices = mesh.indices;
    compute_normals(computed);
    for (size_t v = 0; v < mesh.normals.size(); ++v)
      if (!(glm::dot(mesh.normals[v], mesh.normals[v]) > 1e-12f)) mesh.normals[v] = computed.normals[v];
  }

  // Scene material for glTF material `index` (-1: the glTF default material: single-sided, white
  // in glTF, drawn here in the per-object hashed colour like material-less generated scenes).
  uint32_t material(int index, const std::string& where) {
    auto [it, fresh] = material_cache_.try_emplace(index, 0u);
    if (!fresh) return it->second;
    Material m;
    int texcoord = 0;
    if (index == -1) {
      m.name = "glTF default material";
      m.object_color = true;
    } else {
      const tinygltf::Material& gm = at(m_.materials, index, "material", "materials", where);
      const std::string mw = "material " + std::to_string(index);
      m.name = gm.name.empty() ? mw : gm.name;
      // render_client --save-scene marks generated scenes' per-object colours this way.
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
    it->second = uint32_t(scene_.materials.size());
    scene_.materials.push_back(std::move(m));
    texcoord_of_material_.push_back(texcoord);
    return it->second;
  }

  uint32_t texture(int index, const std::string& where) {
    auto [it, fresh] = texture_cache_.try_emplace(index, 0u);
    if (!fresh) return it->second;
    const tinygltf::Texture& gt = at(m_.textures, index, "texture", "textures", where);
    const std::string tw = "texture " + std::to_string(index);
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
    it->second = uint32_t(scene_.textures.size());
    scene_.textures.push_back(t);
    return it->second;
  }

  // Decodes glTF image `index` (PNG, JPEG, ... through stb_image) to RGBA8.
  uint32_t image(int index, const std::string& where) {
    auto [it, fresh] = image_cache_.try_emplace(index, 0u);
    if (!fresh) return it->second;
    const tinygltf::Image& gi = at(m_.images, index, "image", "images", where);
    const std::string iw = "image " + std::to_string(index);
    const unsigned char* bytes = gi.image.data();
    size_t size = gi.image.size();
    if (gi.bufferView != -1) {
      const tinygltf::BufferView& bv = at(m_.bufferViews, gi.bufferView, "buffer view", "buffer views", iw);
      const tinygltf::Buffer& buf = at(m_.buffers, bv.buffer, "buffer", "buffers", iw);
      if (!fits(bv.byteOffset, 1, bv.byteLength, bv.byteLength, buf.data.size()))
        fail(iw, "buffer view " + std::to_string(gi.bufferView) + " reads past the end of buffer " +
                     std::to_string(bv.buffer));
      bytes = buf.data.data() + bv.byteOffset;
      size = bv.byteLength;
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
    it->second = uint32_t(scene_.images.size());
    scene_.images.push_back(std::move(img));
    return it->second;
  }

  const tinygltf::Model& m_;
  std::string file_;
  Scene scene_;
  std::vector<int> parent_;                     // per node, -1 for roots
  std::map<int, std::vector<int>> mesh_cache_;  // glTF mesh -> scene mesh per primitive (-1: none)
  std::map<int, uint32_t> material_cache_;      // glTF material (-1: default) -> scene material
  std::vector<int> texcoord_of_material_;       // per scene material: its texture's TEXCOORD set
  std::map<int, uint32_t> texture_cache_;       // glTF texture -> scene texture
  std::map<int, uint32_t> image_cache_;         // glTF image -> scene image
  int skipped_ = 0;                             // non-triangle primitives of used meshes
};

// ------------------------------------------------------------------------------------- city

// splitmix64: identical sequence on every platform and standard library.
class Rng {
 public:
  explicit Rng(uint64_t seed) : s_(seed) {}
  int uniform(int lo, int hi) { return lo + int(mix64(s_ += 0x9e3779b97f4a7c15ULL) % uint64_t(hi - lo + 1)); }

 private:
  uint64_t s_;
};

// Appends a rows x cols grid of quads spanning origin + [0,1] u + [0,1] v, front (CCW) side
// facing cross(u, v).
void add_grid(Mesh& m, glm::vec3 origin, glm::vec3 u, glm::vec3 v, int rows, int cols) {
  const glm::vec3 normal = glm::normalize(glm::cross(u, v));
  const auto base = uint32_t(m.positions.size());
  for (int r = 0; r <= rows; ++r)
    for (int c = 0; c <= cols; ++c) {
      m.positions.push_back(origin + u * (float(c) / float(cols)) + v * (float(r) / float(rows)));
      m.normals.push_back(normal);
    }
  auto at = [&](int r, int c) { return base + uint32_t(r * (cols + 1) + c); };
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < cols; ++c)
      m.indices.insert(m.indices.end(),
                       {at(r, c), at(r, c + 1), at(r + 1, c + 1), at(r, c), at(r + 1, c + 1), at(r + 1, c)});
}

// A w x d box building of `floors` floors with its corner at the origin (x in [0,w], z in [0,d]).
// Each facade is a window grid of (floors * detail) rows x (bays * detail) columns, with one
// window bay per facade under 15 m and two otherwise; the roof is one quad, there is no floor.
// Triangles: 4 * rows * detail * (bays(w) + bays(d)) + 2.
Mesh building_mesh(int w, int d, int floors, int detail) {
  Mesh m;
  m.name = "building " + std::to_string(w) + "x" + std::to_string(d) + "x" + std::to_string(floors);
  const auto fw = float(w), fd = float(d), h = float(floors * city::kFloorHeight);
  const glm::vec3 up(0, h, 0);
  const int rows = floors * detail;
  auto cols = [&](int len) { return (len < 15 ? 1 : 2) * detail; };
  add_grid(m, {0, 0, fd}, {fw, 0, 0}, up, rows, cols(w));    // +z
  add_grid(m, {fw, 0, 0}, {-fw, 0, 0}, up, rows, cols(w));   // -z
  add_grid(m, {fw, 0, fd}, {0, 0, -fd}, up, rows, cols(d));  // +x
  add_grid(m, {0, 0, 0}, {0, 0, fd}, up, rows, cols(d));     // -x
  add_grid(m, up, {0, 0, fd}, {fw, 0, 0}, 1, 1);             // roof, +y
  return m;
}

void check_range(const std::string& where, const char* what, int v, int lo, int hi) {
  if (v < lo || v > hi)
    throw InputError(where + ": " + what + " must be " + std::to_string(lo) + ".." + std::to_string(hi) +
                     " (got " + std::to_string(v) + ")");
}

// Limits of the city parameters (also enforced on --scene specs).
constexpr int kMaxBlocks = 1000, kMaxBuildings = 64, kMaxFloors = 200, kMaxDetail = 16, kMaxCopies = 1000;

// ------------------------------------------------------------------------------------- hard cases

// A closed axis-aligned box mesh [lo, hi] (6 faces, 12 triangles), optionally without its +x face
// (an open box the camera can stand in and look out of).
Mesh box_mesh(const std::string& name, glm::vec3 lo, glm::vec3 hi, bool open_plus_x = false) {
  Mesh m;
  m.name = name;
  const glm::vec3 d = hi - lo;
  const glm::vec3 ex(d.x, 0, 0), ey(0, d.y, 0), ez(0, 0, d.z);
  add_grid(m, lo, ez, ey, 1, 1);                    // -x
  if (!open_plus_x) add_grid(m, lo + ex, ey, ez, 1, 1);  // +x
  add_grid(m, lo, ex, ez, 1, 1);                    // -y
  add_grid(m, lo + ey, ez, ex, 1, 1);               // +y
  add_grid(m, lo, ey, ex, 1, 1);                    // -z
  add_grid(m, lo + ez, ex, ey, 1, 1);               // +z
  return m;
}

uint32_t add_mesh(Scene& s, Mesh m) {
  s.meshes.push_back(std::move(m));
  return uint32_t(s.meshes.size() - 1);
}

void place(Scene& s, uint32_t mesh, const glm::dvec3& at, const std::string& name,
           const glm::dvec3& scale = glm::dvec3(1.0)) {
  s.objects.push_back(Object{mesh, glm::scale(glm::translate(glm::dmat4(1.0), at), scale), name});
}

// hard:walls (layout in scene_io.hpp): zero-thickness walls with doors, cubes behind each wall,
// an open box to stand in, an edge-on wall and a flat ground.
Scene hard_walls(int walls) {
  Scene s;
  const uint32_t ground = add_mesh(s, Mesh{});
  add_grid(s.meshes[ground], {-20, 0, -20}, {0, 0, 40}, {20.0f + 10.0f * float(walls + 1), 0, 0}, 1, 1);
  s.meshes[ground].name = "ground (flat box)";
  // A wall in the plane x = 0: y in [0, 4], z in [-6, 6], a door z in [-1, 1], y in [0, 2.5].
  Mesh wall;
  wall.name = "wall (zero thickness)";
  add_grid(wall, {0, 0, -6}, {0, 0, 5}, {0, 4, 0}, 1, 1);
  add_grid(wall, {0, 0, 1}, {0, 0, 5}, {0, 4, 0}, 1, 1);
  add_grid(wall, {0, 2.5f, -1}, {0, 0, 2}, {0, 1.5f, 0}, 1, 1);
  const uint32_t wall_mesh = add_mesh(s, std::move(wall));
  const uint32_t cube = add_mesh(s, box_mesh("unit cube", {0, 0, 0}, {1, 1, 1}));
  const uint32_t open_box = add_mesh(s, box_mesh("open box", {0, 0, 0}, {3, 3, 3}, true));
  Mesh edge;
  edge.name = "edge-on wall";
  add_grid(edge, {0, 0, 0}, {0, 4, 0}, {10.0f * float(walls + 1), 0, 0}, 1, 1);  // plane z = 0
  const uint32_t edge_mesh = add_mesh(s, std::move(edge));

  s.objects.push_back(Object{ground, glm::dmat4(1.0), "ground"});
  place(s, open_box, {-8, 0, -1.5}, "open box");
  place(s, edge_mesh, {0, 0, 8}, "edge-on wall");
  for (int k = 1; k <= walls; ++k) {
    const std::string w = "wall " + std::to_string(k);
    place(s, wall_mesh, {10.0 * k, 0, 0}, w);
    for (int c = 0; c < 3; ++c)
      place(s, cube, {10.0 * k + 4.5, 0, -4.5 + 4.0 * c}, w + " cube " + std::to_string(c));
    place(s, cube, {10.0 * k + 2.0, 0, 2.5}, w + " tower", {1, 5, 1});  // above the wall: partly visible
  }
  return s;
}

// hard:exit (layout in scene_io.hpp): a closed room and a dense field of cubes outside it.
Scene hard_exit(int n) {
  Scene s;
  const uint32_t ground = add_mesh(s, Mesh{});
  add_grid(s.meshes[ground], {-2, 0, float(-n - 2)}, {0, 0, float(2 * n + 8)}, {float(2 * n + 12), 0, 0}, 1, 1);
  s.meshes[ground].name = "ground";
  s.objects.push_back(Object{ground, glm::dmat4(1.0), "ground"});
  place(s, add_mesh(s, box_mesh("room", {0, 0, 0}, {4, 3, 4})), {0, 0, 0}, "room");
  const uint32_t cube = add_mesh(s, box_mesh("cube", {0, 0, 0}, {1.6f, 1, 1.6f}));
  for (int i = 0; i < n; ++i)
    for (int k = 0; k < n; ++k) {
      const double height = 1.5 + 2.5 * double((i * 7 + k * 13) % 11) / 10.0;
      place(s, cube, {6.0 + 2.0 * i, 0, 2.0 - n + 2.0 * k}, "cube " + std::to_string(i) + "," + std::to_string(k),
            {1, height, 1});
    }
  return s;
}

// hard:span: parts from 1e-3 to 1e3 units on a bench, a tiny part behind a tiny plate, inside a
// hall 1e5 wide (inward faces), with 1e4-unit pillars.
Scene hard_span() {
  Scene s;
  const uint32_t cube = add_mesh(s, box_mesh("unit cube", {0, 0, 0}, {1, 1, 1}));
  const uint32_t hall = add_mesh(s, box_mesh("hall", {-0.5f, 0, -0.5f}, {0.5f, 1, 0.5f}));
  place(s, hall, {0, -1, 0}, "hall", {1e5, 2e4, 1e5});
  double x = 0;
  for (int e = -3; e <= 3; ++e) {  // sizes 1e-3 .. 1e3, each on the bench at y = 1
    const double size = std::pow(10.0, e);
    place(s, cube, {x, 1.0, -0.5 * size}, "part 1e" + std::to_string(e), glm::dvec3(size));
    x += 3.0 * size;
  }
  // A 1e-3 part hidden 1e-3 behind a 4e-3 plate (seen from -x), and one peeking out beside it.
  place(s, cube, {-0.01, 1.0, -0.002}, "tiny plate", {1e-4, 4e-3, 4e-3});
  place(s, cube, {-0.0085, 1.0015, -0.0005}, "tiny hidden part", glm::dvec3(1e-3));
  place(s, cube, {-0.0085, 1.0015, 0.0025}, "tiny peeking part", glm::dvec3(1e-3));
  for (int i = 0; i < 4; ++i)
    place(s, cube, {(i % 2 ? 3e4 : -3e4) - 5e2, -1, (i / 2 ? 3e4 : -3e4) - 5e2}, "pillar " + std::to_string(i),
          {1e3, 1e4, 1e3});
  return s;
}

// hard:degenerate: meshes of zero-area triangles (repeated indices, collinear and coincident
// vertices), a cube with degenerate triangles inside it, two huge triangles (1e6), and a field of
// sub-pixel cubes (2e-3) partly behind a wall.
Scene hard_degenerate() {
  Scene s;
  Mesh degenerate;
  degenerate.name = "degenerate triangles only";
  degenerate.positions = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {1, 1, 0}, {1, 1, 0}};
  degenerate.indices = {0, 0, 1, 0, 1, 2, 3, 4, 3, 3, 3, 3, 0, 2, 1, 4, 4, 0};
  degenerate.normals.assign(degenerate.positions.size(), {0, 0, 1});
  const uint32_t degenerate_mesh = add_mesh(s, std::move(degenerate));
  Mesh point;
  point.name = "a single point";
  point.positions = {{0, 0, 0}};
  point.normals = {{0, 1, 0}};
  point.indices = {0, 0, 0};
  const uint32_t point_mesh = add_mesh(s, std::move(point));
  Mesh mixed = box_mesh("cube with degenerate triangles", {0, 0, 0}, {1, 1, 1});
  const auto base = uint32_t(mixed.positions.size());
  mixed.positions.insert(mixed.positions.end(), {{0.5f, 0.5f, 0.5f}, {0.5f, 0.5f, 0.5f}, {0.2f, 0.5f, 0.5f}});
  mixed.normals.insert(mixed.normals.end(), 3, glm::vec3(0, 1, 0));
  mixed.indices.insert(mixed.indices.end(), {base, base + 1, base + 2, 0, 0, 0, 1, 2, 1});
  const uint32_t mixed_mesh = add_mesh(s, std::move(mixed));
  Mesh huge;
  huge.name = "huge triangles";
  huge.positions = {{-1e6f, 0, -1e6f}, {1e6f, 0, -1e6f}, {0, 0, 1e6f},  // ground, y = 0
                    {300, -1e6f, -1e6f}, {300, -1e6f, 1e6f}, {300, 1e6f, 0}};  // backdrop, x = 300
  huge.normals = {{0, 1, 0}, {0, 1, 0}, {0, 1, 0}, {-1, 0, 0}, {-1, 0, 0}, {-1, 0, 0}};
  huge.indices = {0, 2, 1, 3, 4, 5};
  const uint32_t huge_mesh = add_mesh(s, std::move(huge));
  const uint32_t cube = add_mesh(s, box_mesh("unit cube", {0, 0, 0}, {1, 1, 1}));

  s.objects.push_back(Object{huge_mesh, glm::dmat4(1.0), "huge triangles"});
  place(s, degenerate_mesh, {5, 1, -2}, "degenerate triangles");
  place(s, point_mesh, {5, 1, 2}, "point");
  place(s, mixed_mesh, {8, 0.01, -0.5}, "cube with degenerate triangles");
  place(s, cube, {20, 0.01, -3}, "wall", {0.2, 3, 3});
  for (int i = 0; i < 12; ++i)
    for (int j = 0; j < 12; ++j)
      place(s, cube, {25.0 + 2.0 * i, 1.0 + 0.1 * j, -6.0 + 1.0 * j}, "sub-pixel " + std::to_string(i * 12 + j),
            glm::dvec3(2e-3));
  return s;
}

// ------------------------------------------------------------------------------------- specs

// A decimal integer in [lo, hi]: the whole of `text`.
int parse_int(const std::string& spec, const char* what, std::string_view text, int lo, int hi) {
  int v = 0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
  if (ec != std::errc() || end != text.data() + text.size() || v < lo || v > hi)
    throw InputError("--scene '" + spec + "': " + what + " must be " + std::to_string(lo) + ".." +
                     std::to_string(hi) + " (got '" + std::string(text) + "')");
  return v;
}

// "AxB" with both in [1, hi].
std::pair<int, int> parse_dims(const std::string& spec, const char* what, std::string_view text, int hi) {
  const size_t x = text.find('x');
  if (x == std::string_view::npos)
    throw InputError("--scene '" + spec + "': " + what + " must be <X>x<Z>, e.g. 10x10 (got '" +
                     std::string(text) + "')");
  return {parse_int(spec, what, text.substr(0, x), 1, hi), parse_int(spec, what, text.substr(x + 1), 1, hi)};
}

bool ends_with_ci(const std::string& s, std::string_view suffix) {
  if (s.size() < suffix.size()) return false;
  for (size_t i = 0; i < suffix.size(); ++i)
    if (std::tolower(static_cast<unsigned char>(s[s.size() - suffix.size() + i])) != suffix[i]) return false;
  return true;
}

}  // namespace

Scene load_gltf(const std::string& path) {
  const std::vector<unsigned char> bytes = read_file(path);
  if (bytes.size() > UINT_MAX) throw InputError(path + ": file larger than 4 GiB");
  // .glb / .gltf by extension, anything else by the binary magic.
  const bool binary = ends_with_ci(path, ".glb") || (!ends_with_ci(path, ".gltf") && bytes.size() >= 4 &&
                                                     std::memcmp(bytes.data(), "glTF", 4) == 0);
  tinygltf::TinyGLTF loader;
  loader.SetImageLoader(keep_image_bytes, nullptr);
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
  return scene;
}

// Lot (a, b) of block (i, j) holds building k = a * n + b with footprint w x d (10..20 m in 2 m
// steps) at a random offset inside the lot and 1..floors_max floors; meshes are shared between
// buildings of equal (w, d, floors). Each block also has a ground square (the block plus half of
// the surrounding streets, so the ground tiles the city). Sizes (checked by the scene tests):
//   city (10x10:4:12:2)   1700 objects,   500,488 triangles drawn
//   city:20x20:4:16:2     6800 objects, 2,613,280 triangles drawn (the >= 2M scene)
Scene generate_city(const CityParams& p) {
  check_range("city", "blocks", p.blocks_x, 1, kMaxBlocks);
  check_range("city", "blocks", p.blocks_z, 1, kMaxBlocks);
  check_range("city", "buildings per block", p.buildings_per_block, 1, kMaxBuildings);
  check_range("city", "floors", p.floors_max, 1, kMaxFloors);
  check_range("city", "detail", p.detail, 1, kMaxDetail);

  Scene scene;
  scene.source = "city";
  const auto pitch = float(city::block_pitch(p));
  Mesh ground;
  ground.name = "ground";
  add_grid(ground, {0, 0, 0}, {0, 0, pitch}, {pitch, 0, 0}, 1, 1);
  scene.meshes.push_back(std::move(ground));

  Rng rng(p.seed);
  std::map<std::tuple<int, int, int>, uint32_t> cache;  // (w, d, floors) -> mesh
  const int n = p.buildings_per_block;
  for (int i = 0; i < p.blocks_x; ++i)
    for (int j = 0; j < p.blocks_z; ++j) {
      const std::string block = "block " + std::to_string(i) + "," + std::to_string(j);
      const Aabb area = city::block_area(p, i, j);
      const glm::dvec3 corner = area.min - glm::dvec3(0.5 * city::kStreet, 0, 0.5 * city::kStreet);
      scene.objects.push_back(Object{0, glm::translate(glm::dmat4(1.0), corner), block + " ground"});
      for (int k = 0; k < n * n; ++k) {
        const int w = 2 * rng.uniform(5, 10), d = 2 * rng.uniform(5, 10),
                  floors = rng.uniform(1, p.floors_max);
        const int ox = rng.uniform(0, int(city::kLot) - w), oz = rng.uniform(0, int(city::kLot) - d);
        const glm::dvec3 lot = area.min + glm::dvec3(k / n, 0, k % n) * city::kLot;
        auto [it, fresh] = cache.try_emplace({w, d, floors}, uint32_t(scene.meshes.size()));
        if (fresh) scene.meshes.push_back(building_mesh(w, d, floors, p.detail));
        scene.objects.push_back(Object{it->second,
                                       glm::translate(glm::dmat4(1.0), lot + glm::dvec3(ox, 0, oz)),
                                       block + " building " + std::to_string(k)});
      }
    }
  return scene;
}

// Copy (i, j) is translated by (i * spacing_x, 0, j * spacing_z) from the asset's placement.
Scene layout_grid(const Scene& asset, int nx, int nz, double gap) {
  check_range("layout", "copies", nx, 1, kMaxCopies);
  check_range("layout", "copies", nz, 1, kMaxCopies);
  Scene scene;
  scene.source = "layout " + std::to_string(nx) + "x" + std::to_string(nz) + " of " + asset.source;
  scene.meshes = asset.meshes;
  scene.materials = asset.materials;
  scene.textures = asset.textures;
  scene.images = asset.images;
  const glm::dvec3 spacing = asset.bounds().extent() * (1.0 + gap);
  scene.objects.reserve(size_t(nx) * size_t(nz) * asset.objects.size());
  for (int i = 0; i < nx; ++i)
    for (int j = 0; j < nz; ++j) {
      const glm::dmat4 t = glm::translate(glm::dmat4(1.0), glm::dvec3(i * spacing.x, 0, j * spacing.z));
      const std::string prefix = "copy " + std::to_string(i) + "," + std::to_string(j) + "/";
      for (const Object& o : asset.objects)
        scene.objects.push_back(Object{o.mesh, t * o.transform, prefix + o.name});
    }
  return scene;
}

Scene load_scene(const std::string& spec) {
  // Fields split at ':'; the last field keeps any further colons (layout paths).
  auto split = [&](size_t max_fields) {
    std::vector<std::string_view> f;
    std::string_view rest = spec;
    for (size_t c; f.size() + 1 < max_fields && (c = rest.find(':')) != std::string_view::npos;) {
      f.push_back(rest.substr(0, c));
      rest.remove_prefix(c + 1);
    }
    f.push_back(rest);
    return f;
  };
  Scene scene;
  if (spec.rfind("offset:", 0) == 0) {
    const auto f = split(3);
    if (f.size() != 3 || f[2].empty())
      throw InputError("--scene '" + spec + "': expected offset:DX,DY,DZ:<scene spec>");
    glm::dvec3 d{};
    std::string_view rest = f[1];
    for (int axis = 0; axis < 3; ++axis) {
      const size_t comma = rest.find(',');
      if ((axis < 2) != (comma != std::string_view::npos))
        throw InputError("--scene '" + spec + "': offset must be DX,DY,DZ (got '" + std::string(f[1]) + "')");
      const std::string text(rest.substr(0, comma));
      char* end = nullptr;
      errno = 0;
      const double v = text.empty() ? NAN : std::strtod(text.c_str(), &end);
      if (text.empty() || end != text.c_str() + text.size() || !std::isfinite(v) || std::abs(v) > 1e9)
        throw InputError("--scene '" + spec + "': offset component '" + text +
                         "' must be a finite number with |v| <= 1e9");
      d[axis] = v;
      rest.remove_prefix(comma == std::string_view::npos ? rest.size() : comma + 1);
    }
    scene = load_scene(std::string(f[2]));
    const glm::dmat4 t = glm::translate(glm::dmat4(1.0), d);
    for (Object& o : scene.objects) o.transform = t * o.transform;
  } else if (spec.rfind("hard:", 0) == 0) {
    const auto f = split(3);
    const std::string_view kind = f[1];
    if (kind == "walls" && f.size() <= 3) {
      scene = hard_walls(f.size() == 3 ? parse_int(spec, "walls", f[2], 1, 100) : 5);
    } else if (kind == "exit" && f.size() <= 3) {
      scene = hard_exit(f.size() == 3 ? parse_int(spec, "field", f[2], 2, 100) : 16);
    } else if (kind == "span" && f.size() == 2) {
      scene = hard_span();
    } else if (kind == "degenerate" && f.size() == 2) {
      scene = hard_degenerate();
    } else {
      throw InputError("--scene '" + spec + "': unknown hard case; expected hard:walls[:N], hard:exit[:N], hard:span or hard:degenerate");
    }
  } else if (spec.rfind("layout:", 0) == 0) {
    const auto f = split(3);
    if (f.size() != 3 || f[2].empty())
      throw InputError("--scene '" + spec + "': expected layout:NXxNZ:path.gltf|.glb");
    const auto [nx, nz] = parse_dims(spec, "copies", f[1], kMaxCopies);
    scene = layout_grid(load_gltf(std::string(f[2])), nx, nz, 0.25);
  } else if (spec == "city" || spec.rfind("city:", 0) == 0) {
    const auto f = split(6);
    if (f.size() > 5) throw InputError("--scene '" + spec + "': expected city[:BXxBZ[:N[:F[:D]]]]");
    CityParams p;
    if (f.size() > 1) std::tie(p.blocks_x, p.blocks_z) = parse_dims(spec, "blocks", f[1], kMaxBlocks);
    if (f.size() > 2) p.buildings_per_block = parse_int(spec, "buildings per block", f[2], 1, kMaxBuildings);
    if (f.size() > 3) p.floors_max = parse_int(spec, "floors", f[3], 1, kMaxFloors);
    if (f.size() > 4) p.detail = parse_int(spec, "detail", f[4], 1, kMaxDetail);
    scene = generate_city(p);
  } else if (spec.rfind("plant:", 0) == 0) {
    const std::string text = spec.substr(6);
    const std::optional<double> m = parse_finite(text);
    if (!m || !(*m >= plant::kMinMillions && *m <= plant::kMaxMillions))
      throw InputError("--scene '" + spec + "': millions of triangles must be a number in 0.01..200 (got '" + text +
                       "')");
    scene = plant::generate_plant(plant::PlantParams{*m, 1});
  } else if (ends_with_ci(spec, ".gltf") || ends_with_ci(spec, ".glb")) {
    scene = load_gltf(spec);
  } else {
    throw InputError("--scene '" + spec +
                     "': unknown scene; expected path.gltf, path.glb, city[:BXxBZ[:N[:F[:D]]]] "
                     "(blocks, buildings per block side, max floors, detail), layout:NXxNZ:path.gltf|.glb, "
                     "plant:M (M million triangles), hard:walls[:N], hard:exit[:N], hard:span, hard:degenerate or "
                     "offset:DX,DY,DZ:<spec>");
  }
  scene.source = spec;
  return scene;
}

}  // namespace occ
