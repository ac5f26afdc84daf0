#include "common/scene/scene.hpp"

#include <meshoptimizer.h>
#include <sys/stat.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <numeric>
#include <span>
#include <stdexcept>

#include "common/hash.hpp"

namespace occ {

Aabb Mesh::box() const {
  if (released) return released_box;
  Aabb b;
  for (uint32_t i : indices) b.grow(glm::dvec3(positions[i]));
  return b;
}

void Mesh::release_geometry() {
  if (released) return;
  released_box = box();
  released_triangles = indices.size() / 3;
  released_vertices = positions.size();
  released = true;
  std::vector<glm::vec3>().swap(positions);
  std::vector<glm::vec3>().swap(normals);
  std::vector<uint32_t>().swap(indices);
  std::vector<glm::vec2>().swap(uvs);
  std::vector<uint32_t>().swap(colors);
}

std::optional<SourceFile> source_file(const std::string& path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) return std::nullopt;
  return SourceFile{path, uint64_t(st.st_size), int64_t(st.st_mtim.tv_sec) * 1000000000 + st.st_mtim.tv_nsec};
}

Mesh read_mapped_mesh(const Scene& scene, uint32_t m) {
  const Mesh& me = scene.meshes[m];
  Mesh out;
  out.name = me.name;
  out.material = me.material;
  out.flat = me.flat;
  out.clusters = me.clusters;
  if (!me.released || !scene.mapped) throw std::logic_error("read_mapped_mesh: mesh " + std::to_string(m) + " is in memory");
  const MappedMesh& mm = scene.mapped->meshes[m];
  auto read = [&](const MappedArray& a, auto& v) {
    v.resize(a.count);
    if (a.bytes) scene.mapped->file->read(a.offset, a.bytes, reinterpret_cast<uint8_t*>(v.data()));
  };
  read(mm.positions, out.positions);
  read(mm.normals, out.normals);
  read(mm.indices, out.indices);
  read(mm.uvs, out.uvs);
  read(mm.colors, out.colors);
  for (uint32_t i : out.indices)
    if (i >= out.positions.size())
      throw std::runtime_error(scene.mapped->path() + ": mesh " + std::to_string(m) + ": index " + std::to_string(i) +
                               " out of range: the cache is corrupt; delete it");
  return out;
}

bool Scene::mesh_has_colors(uint32_t m) const {
  const Mesh& me = meshes[m];
  if (me.released && mapped) return mapped->meshes[m].colors.count == me.released_vertices && me.released_vertices;
  return !me.colors.empty() && me.colors.size() == me.positions.size();
}

bool Scene::mesh_has_uvs(uint32_t m) const {
  const Mesh& me = meshes[m];
  if (me.released && mapped) return mapped->meshes[m].uvs.count == me.released_vertices && me.released_vertices;
  return !me.uvs.empty() && me.uvs.size() == me.positions.size();
}

bool Scene::geometry_released() const {
  return std::any_of(meshes.begin(), meshes.end(), [](const Mesh& m) { return m.released; });
}

Aabb Scene::bounds() const {
  std::vector<Aabb> mesh_boxes(meshes.size());
  for (size_t m = 0; m < meshes.size(); ++m) mesh_boxes[m] = meshes[m].box();
  Aabb b;
  for (const Object& o : objects) b.grow(mesh_boxes[o.mesh].transformed(o.transform));
  return b;
}

uint64_t Scene::triangle_count() const {
  uint64_t n = 0;
  for (const Object& o : objects) n += meshes[o.mesh].triangle_count();
  return n;
}

const char* alpha_mode_name(AlphaMode m) {
  switch (m) {
    case AlphaMode::Opaque: return "OPAQUE";
    case AlphaMode::Mask: return "MASK";
    case AlphaMode::Blend: return "BLEND";
  }
  return "?";
}

uint64_t Scene::content_hash() const {
  if (geometry_released())
    throw std::logic_error("Scene::content_hash: the geometry of " + source + " was released after its upload");
  Hasher h;
  h.u64(meshes.size());
  for (const Mesh& m : meshes) {
    h.bytes(m.positions.data(), m.positions.size() * sizeof(glm::vec3));
    h.bytes(m.indices.data(), m.indices.size() * sizeof(uint32_t));
    if (m.flat) h.u32(0x666c6174);  // "flat" (scenes without it hash as before)
    if (m.material != kNoMaterial || !m.uvs.empty() || !m.colors.empty()) {  // generated scenes hash as before
      h.u32(m.material);
      h.u64(m.uvs.size());
      h.bytes(m.uvs.data(), m.uvs.size() * sizeof(glm::vec2));
      h.u64(m.colors.size());
      h.bytes(m.colors.data(), m.colors.size() * sizeof(uint32_t));
    }
  }
  h.u64(objects.size());
  for (const Object& o : objects) {
    h.u32(o.mesh);
    for (int c = 0; c < 4; ++c)
      for (int r = 0; r < 4; ++r) h.f64(o.transform[c][r]);
  }
  if (!materials.empty()) {
    h.u64(materials.size());
    for (const Material& mat : materials) {
      for (int c = 0; c < 4; ++c) h.f64(mat.base_color[c]);
      h.u32(uint32_t(mat.base_color_texture));
      h.u32(uint32_t(mat.alpha_mode));
      h.f64(mat.alpha_cutoff);
      h.u32(uint32_t(mat.double_sided) | uint32_t(mat.unlit) << 1 | uint32_t(mat.object_color) << 2);
    }
    h.u64(textures.size());
    for (const Texture& t : textures) {
      h.u32(t.image);
      h.u32(uint32_t(t.sampler.mag_filter));
      h.u32(uint32_t(t.sampler.min_filter));
      h.u32(uint32_t(t.sampler.wrap_s));
      h.u32(uint32_t(t.sampler.wrap_t));
    }
    h.u64(images.size());
    for (const Image& img : images) {
      h.u32(uint32_t(img.width));
      h.u32(uint32_t(img.height));
      h.bytes(img.rgba.data(), img.rgba.size());
    }
  }
  return h.value();
}

void compute_normals(Mesh& mesh) {
  std::vector<glm::dvec3> acc(mesh.positions.size(), glm::dvec3(0.0));
  for (size_t t = 0; t + 2 < mesh.indices.size(); t += 3) {
    uint32_t a = mesh.indices[t], b = mesh.indices[t + 1], c = mesh.indices[t + 2];
    glm::dvec3 pa(mesh.positions[a]), pb(mesh.positions[b]), pc(mesh.positions[c]);
    glm::dvec3 n = glm::cross(pb - pa, pc - pa);  // length = 2 * area: area weighting
    acc[a] += n;
    acc[b] += n;
    acc[c] += n;
  }
  mesh.normals.resize(mesh.positions.size());
  for (size_t i = 0; i < acc.size(); ++i) {
    double l = glm::length(acc[i]);
    mesh.normals[i] = l > 0 ? glm::vec3(acc[i] / l) : glm::vec3(0, 1, 0);
  }
}

void repair_normals(Mesh& mesh) {
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

namespace {

// Removes, in place and keeping the others' order, the triangles (a, b, c) for which
// drop(a, b, c) is true, and returns how many.
template <class Drop>
uint64_t remove_triangles_if(Mesh& mesh, Drop drop) {
  size_t kept = 0;
  for (size_t t = 0; t + 2 < mesh.indices.size(); t += 3) {
    const uint32_t a = mesh.indices[t], b = mesh.indices[t + 1], c = mesh.indices[t + 2];
    if (drop(a, b, c)) continue;
    mesh.indices[kept++] = a;
    mesh.indices[kept++] = b;
    mesh.indices[kept++] = c;
  }
  const uint64_t dropped = (mesh.indices.size() - kept) / 3;
  mesh.indices.resize(kept);
  return dropped;
}

}  // namespace

uint64_t drop_zero_area_triangles(Mesh& mesh) {
  constexpr double kCollinearUlps = 8;
  return remove_triangles_if(mesh, [&](uint32_t a, uint32_t b, uint32_t c) {
    // Float differences and their products are exact in double: zero only when collinear. The
    // height over the longest edge, |n| / longest, below a few float ulps of the coordinates is
    // rounding noise: collinear at the precision the positions are stored in.
    const glm::dvec3 pa(mesh.positions[a]), pb(mesh.positions[b]), pc(mesh.positions[c]);
    const glm::dvec3 n = glm::cross(pb - pa, pc - pa);
    if (n.x == 0 && n.y == 0 && n.z == 0) return true;
    const double longest = std::sqrt(std::max({glm::dot(pb - pa, pb - pa), glm::dot(pc - pb, pc - pb),
                                               glm::dot(pa - pc, pa - pc)}));
    double magnitude = 0;
    for (const glm::dvec3& p : {pa, pb, pc}) magnitude = std::max({magnitude, std::abs(p.x), std::abs(p.y), std::abs(p.z)});
    return glm::length(n) <= longest * kCollinearUlps * magnitude * 0x1p-23;
  });
}

namespace {

// A triangle as drop_repeated_triangles compares it: its positions' bits, the corner with the
// smallest first, and its vertices in that order (a rotation: the same winding).
struct TriangleKey {
  std::array<uint32_t, 9> bits;
  std::array<uint32_t, 3> vertices;
};

TriangleKey triangle_key(const Mesh& m, uint32_t a, uint32_t b, uint32_t c) {
  std::array<std::array<uint32_t, 3>, 3> p;
  const uint32_t v[3] = {a, b, c};
  for (int k = 0; k < 3; ++k) {
    const glm::vec3& q = m.positions[v[k]];
    p[k] = {std::bit_cast<uint32_t>(q.x), std::bit_cast<uint32_t>(q.y), std::bit_cast<uint32_t>(q.z)};
  }
  const int f = int(std::min_element(p.begin(), p.end()) - p.begin());
  TriangleKey key;
  for (int k = 0; k < 3; ++k) {
    std::copy(p[(f + k) % 3].begin(), p[(f + k) % 3].end(), key.bits.begin() + 3 * k);
    key.vertices[k] = v[(f + k) % 3];
  }
  return key;
}

struct KeyBitsHash {
  size_t operator()(const std::array<uint32_t, 9>& k) const {
    uint64_t h = 0;
    for (uint32_t v : k) h = mix64(h ^ v);
    return size_t(h);
  }
};

// Whether vertices u and v draw alike: the same texture coordinates and colour, and normals
// equal or opposite (the Shaded pass lights |n.l|, scene_shaders.cpp). Positions are compared
// by the caller.
bool corners_alike(const Mesh& m, uint32_t u, uint32_t v) {
  if (!m.uvs.empty() && m.uvs[u] != m.uvs[v]) return false;
  if (!m.colors.empty() && m.colors[u] != m.colors[v]) return false;
  if (!m.normals.empty() && m.normals[u] != m.normals[v] && m.normals[u] != -m.normals[v]) return false;
  return true;
}

}  // namespace

uint64_t drop_repeated_triangles(Mesh& mesh, bool either_winding) {
  // The key of the triangle at indices[3t..3t+3), in the winding that compares.
  auto key_of = [&](size_t t) {
    const uint32_t a = mesh.indices[3 * t], b = mesh.indices[3 * t + 1], c = mesh.indices[3 * t + 2];
    TriangleKey key = triangle_key(mesh, a, b, c);
    if (either_winding) {
      TriangleKey reversed = triangle_key(mesh, a, c, b);
      if (reversed.bits < key.bits) key = reversed;
    }
    return key;
  };
  // An open-addressing table of the first triangle of each key, by its place among the kept
  // triangles (kept triangles never move again) beside the high half of its key's hash: 8 bytes
  // a slot, a key recomputed to compare only where the hashes agree.
  const size_t tris = mesh.indices.size() / 3;
  size_t slots = 16;
  while (slots < 2 * tris) slots *= 2;
  constexpr uint64_t kEmpty = ~uint64_t(0);
  std::vector<uint64_t> table(slots, kEmpty);
  size_t kept = 0;
  // Keys and hashes a batch at a time, their slots prefetched: the table is far larger than the
  // caches, and the loads of a batch overlap.
  constexpr size_t kBatch = 32;
  TriangleKey keys[kBatch];
  uint64_t hashes[kBatch];
  for (size_t t = 0; t < tris; ++t) {
    if (t % kBatch == 0)
      for (size_t i = 0; i < kBatch && t + i < tris; ++i) {
        keys[i] = key_of(t + i);
        hashes[i] = KeyBitsHash{}(keys[i].bits);
        __builtin_prefetch(&table[hashes[i] & (slots - 1)]);
      }
    const TriangleKey& key = keys[t % kBatch];
    bool repeat = false;
    const uint64_t h = hashes[t % kBatch], tag = h >> 32 << 32;
    for (size_t s = h & (slots - 1);; s = (s + 1) & (slots - 1)) {
      if (table[s] == kEmpty) {
        table[s] = tag | kept;
        break;
      }
      if ((table[s] >> 32 << 32) != tag) continue;
      const TriangleKey first = key_of(table[s] & 0xffffffffu);
      if (first.bits != key.bits) continue;
      repeat = true;
      for (int k = 0; k < 3 && repeat; ++k) repeat = corners_alike(mesh, first.vertices[k], key.vertices[k]);
      break;
    }
    if (repeat) continue;
    std::copy_n(mesh.indices.begin() + std::ptrdiff_t(3 * t), 3, mesh.indices.begin() + std::ptrdiff_t(3 * kept));
    ++kept;
  }
  mesh.indices.resize(3 * kept);
  return tris - kept;
}

namespace {

// Recursively splits triangles [begin, end) of `order` at the median centroid along the longest
// axis of the centroid bounds until each part has at most max_tris; appends clusters in order.
void split_range(const Mesh& m, const std::vector<glm::dvec3>& centroid, std::vector<uint32_t>& order,
                 size_t begin, size_t end, uint32_t max_tris, std::vector<std::pair<size_t, size_t>>& out) {
  if (end - begin <= max_tris) {
    out.emplace_back(begin, end);
    return;
  }
  Aabb cb;
  for (size_t i = begin; i < end; ++i) cb.grow(centroid[order[i]]);
  glm::dvec3 e = cb.extent();
  int axis = (e.x >= e.y && e.x >= e.z) ? 0 : (e.y >= e.z ? 1 : 2);
  size_t mid = begin + (end - begin) / 2;
  std::nth_element(order.begin() + begin, order.begin() + mid, order.begin() + end,
                   [&](uint32_t a, uint32_t b) {
                     double ca = centroid[a][axis], cb2 = centroid[b][axis];
                     return ca < cb2 || (ca == cb2 && a < b);  // total order: deterministic
                   });
  split_range(m, centroid, order, begin, mid, max_tris, out);
  split_range(m, centroid, order, mid, end, max_tris, out);
}

// Renumbers the mesh's vertices: vertex i becomes remap[i] (meshoptimizer's remap tables), keeping
// `kept` of them; every per-vertex array and the indices follow.
void remap_vertices(Mesh& m, const std::vector<unsigned int>& remap, size_t kept) {
  const size_t n = m.positions.size();
  meshopt_remapIndexBuffer(m.indices.data(), m.indices.data(), m.indices.size(), remap.data());
  auto apply = [&](auto& v) {
    if (v.size() != n) return;
    meshopt_remapVertexBuffer(v.data(), v.data(), n, sizeof(v[0]), remap.data());
    v.resize(kept);
    v.shrink_to_fit();
  };
  apply(m.positions);
  apply(m.normals);
  apply(m.uvs);
  apply(m.colors);
}

// Meshes of more vertices than this have their clusters ordered for the vertex cache by
// optimize_clusters_for_vertex_cache.
constexpr size_t kLocalVertexCacheAbove = size_t(1) << 16;

// meshopt_optimizeVertexCache on each range of triangles, with the range's vertices renumbered
// 0..k-1 in their order for the call: its cost is then the range's, not the mesh's vertex count
// (a scan of millions of triangles in thousands of clusters). The order it gives may differ from
// a call with the mesh's numbers (the scene cache's version 7 marks the change).
void optimize_clusters_for_vertex_cache(Mesh& m, const std::vector<std::pair<size_t, size_t>>& ranges) {
  constexpr uint32_t kNone = 0xffffffffu;
  std::vector<uint32_t> local(m.positions.size(), kNone), used, tmp;
  for (auto [b, e] : ranges) {
    const std::span<uint32_t> idx(m.indices.data() + 3 * b, 3 * (e - b));
    used.clear();
    for (uint32_t v : idx)
      if (local[v] == kNone) {
        local[v] = 0;
        used.push_back(v);
      }
    std::sort(used.begin(), used.end());
    for (size_t k = 0; k < used.size(); ++k) local[used[k]] = uint32_t(k);
    tmp.resize(idx.size());
    for (size_t i = 0; i < idx.size(); ++i) tmp[i] = local[idx[i]];
    meshopt_optimizeVertexCache(tmp.data(), tmp.data(), tmp.size(), used.size());
    for (size_t i = 0; i < idx.size(); ++i) idx[i] = used[tmp[i]];
    for (uint32_t v : used) local[v] = kNone;
  }
}

}  // namespace

// Merges vertices equal in every attribute (position, normal, uv, colour), keeping first-use
// order (meshoptimizer's remap): exporters often repeat them per face or per primitive, and a
// repeated vertex is shaded again even when its index would have hit the vertex cache.
void weld_vertices(Mesh& m) {
  const size_t n = m.positions.size();
  if (n == 0 || m.indices.empty() || m.normals.size() != n) return;
  std::vector<meshopt_Stream> streams = {{m.positions.data(), sizeof(glm::vec3), sizeof(glm::vec3)},
                                         {m.normals.data(), sizeof(glm::vec3), sizeof(glm::vec3)}};
  if (m.uvs.size() == n) streams.push_back({m.uvs.data(), sizeof(glm::vec2), sizeof(glm::vec2)});
  if (m.colors.size() == n) streams.push_back({m.colors.data(), sizeof(uint32_t), sizeof(uint32_t)});
  std::vector<unsigned int> remap(n);
  const size_t unique = meshopt_generateVertexRemapMulti(remap.data(), m.indices.data(), m.indices.size(), n,
                                                         streams.data(), streams.size());
  if (unique == n) return;
  remap_vertices(m, remap, unique);
}

void split_mesh_clusters(Scene& scene, uint32_t max_triangles) {
  max_triangles = std::max<uint32_t>(max_triangles, 1);
  for (Mesh& m : scene.meshes) {
    m.clusters.clear();
    weld_vertices(m);
    const size_t tris = m.indices.size() / 3;
    if (tris == 0) continue;
    std::vector<std::pair<size_t, size_t>> ranges;
    if (tris <= max_triangles) {
      ranges.emplace_back(0, tris);
    } else {
      std::vector<glm::dvec3> centroid(tris);
      for (size_t t = 0; t < tris; ++t)
        centroid[t] = (glm::dvec3(m.positions[m.indices[3 * t]]) +
                       glm::dvec3(m.positions[m.indices[3 * t + 1]]) +
                       glm::dvec3(m.positions[m.indices[3 * t + 2]])) / 3.0;
      std::vector<uint32_t> order(tris);
      std::iota(order.begin(), order.end(), 0u);
      split_range(m, centroid, order, 0, tris, max_triangles, ranges);
      // nth_element left each cluster's triangles in no order: back to the file's order first
      // (deterministic), the vertex cache order below starts from it.
      for (auto [b, e] : ranges) std::sort(order.begin() + std::ptrdiff_t(b), order.begin() + std::ptrdiff_t(e));
      std::vector<uint32_t> reordered(m.indices.size());
      for (size_t i = 0; i < tris; ++i)
        std::copy_n(m.indices.begin() + 3 * order[i], 3, reordered.begin() + 3 * i);
      m.indices.swap(reordered);
    }
    // Each cluster's triangles in vertex cache order (meshoptimizer): llvmpipe shades a vertex
    // again whenever its index misses a small direct-mapped cache of recent indices, and the
    // order above (or a file's own) may reuse vertices far apart.
    // A big mesh's clusters one at a time with their own vertex numbers (the call's cost grows
    // with the vertex count it is given, once per cluster).
    if (m.positions.size() > kLocalVertexCacheAbove)
      optimize_clusters_for_vertex_cache(m, ranges);
    else
      for (auto [b, e] : ranges)
        meshopt_optimizeVertexCache(m.indices.data() + 3 * b, m.indices.data() + 3 * b, 3 * (e - b),
                                    m.positions.size());
    // Then the vertices renumbered in the order the triangles first use them (meshoptimizer's
    // vertex fetch order): a cache keyed by the index finds neighbouring triangles' vertices at
    // neighbouring numbers instead of colliding. Same triangles, same order, same vertex values:
    // the same pixels (measured no slower on llvmpipe).
    std::vector<unsigned int> remap(m.positions.size());
    const size_t used =
        meshopt_optimizeVertexFetchRemap(remap.data(), m.indices.data(), m.indices.size(), m.positions.size());
    remap_vertices(m, remap, used);
    for (auto [b, e] : ranges) {
      MeshCluster c{uint32_t(3 * b), uint32_t(3 * (e - b)), {}};
      for (size_t i = 3 * b; i < 3 * e; ++i) c.box.grow(glm::dvec3(m.positions[m.indices[i]]));
      m.clusters.push_back(c);
    }
  }
}

}  // namespace occ
