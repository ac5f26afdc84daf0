// SceneGpu's streaming mode (scene_gpu.hpp, SceneUpload::budget_bytes): the GeometryPool over
// every piece and the loader that reads a piece from the mapped caches or the CPU copies.
#include <cstdio>
#include <cstring>
#include <stdexcept>
#include <string>

#include <errno.h>

#include "common/gl/scene_gpu.hpp"

namespace occ {

using namespace gl_detail;

namespace {

const glm::vec3 kUnitZ(0.0f, 0.0f, 1.0f);  // the normal of a vertex without one

// A piece's arrays wherever they are (a mapped cache or CPU vectors): not aligned, read with
// memcpy. Absent arrays are null.
struct PieceArrays {
  const uint8_t *positions = nullptr, *normals = nullptr, *colors = nullptr, *uvs = nullptr, *objects = nullptr,
                *indices = nullptr;
  uint64_t vertices = 0, indices_count = 0;
};

template <class T>
const uint8_t* bytes_of(const std::vector<T>& v) {
  return v.empty() ? nullptr : reinterpret_cast<const uint8_t*>(v.data());
}

// A mesh left in a cache file, read into `buf` (one read of its arrays' span).
PieceArrays mapped_arrays(const MappedGeometry& g, const MappedMesh& mm, std::vector<uint8_t>& buf) {
  const uint64_t base = g.read(mm, buf);
  auto at = [&](const MappedArray& a) { return a.count ? buf.data() + (a.offset - base) : nullptr; };
  return {at(mm.positions), at(mm.normals), at(mm.colors), at(mm.uvs), at(mm.objects), at(mm.indices),
          mm.positions.count, mm.indices.count};
}

// Writes the vertices (position, normal, RGBA8: kUnitBytes each) and indices of a piece into
// `out`, the uvs (zero without) into *uvs; `color_of(v)` gives vertex v's colour. Throws for an
// index out of range, naming `what`.
template <class ColorOf>
void write_piece(const PieceArrays& a, const ColorOf& color_of, std::vector<uint8_t>& out,
                 std::vector<glm::vec2>* uvs, bool with_uvs, const std::string& what) {
  const uint64_t nv = a.vertices, ni = a.indices_count;
  out.resize(nv * GeometryPool::kUnitBytes + ni * 4);
  uint8_t* v = out.data();
  for (uint64_t k = 0; k < nv; ++k, v += GeometryPool::kUnitBytes) {
    std::memcpy(v, a.positions + k * 12, 12);
    if (a.normals) std::memcpy(v + 12, a.normals + k * 12, 12);
    else std::memcpy(v + 12, &kUnitZ, 12);
    const uint32_t rgba = color_of(k);
    std::memcpy(v + 24, &rgba, 4);
  }
  if (ni) std::memcpy(v, a.indices, ni * 4);
  for (uint64_t k = 0; k < ni; ++k) {
    uint32_t i;
    std::memcpy(&i, v + k * 4, 4);
    if (i >= nv) throw std::runtime_error(what + ": index " + std::to_string(i) + " out of range (" +
                                          std::to_string(nv) + " vertices): the cache is corrupt; delete it");
  }
  if (uvs) {
    uvs->resize(nv, glm::vec2(0.0f));
    if (with_uvs && a.uvs) std::memcpy(uvs->data(), a.uvs, nv * 8);
  }
}

}  // namespace

bool SceneGpu::streams(const Scene& scene, const LodData* lod, const SceneUpload& upload) {
  if (scene.mapped || (lod && lod->mapped())) return true;  // the arrays are in the file: read as pieces
  if (upload.budget_bytes == 0) return false;
  uint64_t bytes = 0;  // the resident upload's vertices and indices
  auto add = [&](uint64_t vertices, uint64_t triangles) { bytes += vertices * GeometryPool::kUnitBytes + triangles * 12; };
  for (const Mesh& m : scene.meshes) add(m.vertex_count(), m.triangle_count());
  if (lod)
    for (const auto* list : {&lod->cluster_lods(), &lod->hlods()})
      for (const LodMesh& m : *list) add(m.vertex_count(), m.triangles());
  return bytes > upload.budget_bytes;
}

void SceneGpu::start_pool(const Scene& scene, const LodData* lod, std::vector<const LodMesh*> lod_meshes,
                          const SceneUpload& upload, std::vector<uint8_t> mesh_textured, bool any_textured) {
  std::vector<GeometryPool::PieceSize> sizes;
  sizes.reserve(scene.meshes.size() + lod_meshes.size());
  for (const Mesh& m : scene.meshes) sizes.push_back({m.vertex_count(), m.triangle_count() * 3});
  for (const LodMesh* m : lod_meshes) sizes.push_back({m->vertex_count(), m->triangles() * 3});
  const uint32_t M = uint32_t(scene.meshes.size());
  auto loader = [this, &scene, lod, lod_meshes = std::move(lod_meshes), textured = std::move(mesh_textured), M,
                 buf = std::vector<uint8_t>()](uint32_t p, std::vector<uint8_t>& out,
                                               std::vector<glm::vec2>* uvs) mutable {
    if (p < M) {
      const Mesh& me = scene.meshes[p];
      PieceArrays a;
      if (me.released && scene.mapped) {
        a = mapped_arrays(*scene.mapped, scene.mapped->meshes[p], buf);
      } else {
        a = {bytes_of(me.positions), bytes_of(me.normals), bytes_of(me.colors), bytes_of(me.uvs), nullptr,
             bytes_of(me.indices), me.positions.size(), me.indices.size()};
      }
      const bool colored = scene.mesh_has_colors(p);
      auto color_of = [&](uint64_t v) {
        uint32_t c = 0xffffffffu;
        if (colored) std::memcpy(&c, a.colors + v * 4, 4);
        return c;
      };
      const std::string& file = me.released && scene.mapped ? scene.mapped->path() : scene.source;
      write_piece(a, color_of, out, uvs, textured[p] != 0, file + ": mesh " + std::to_string(p));
      return;
    }
    const LodMesh& m = *lod_meshes[p - M];
    const MappedGeometry* g = m.released ? lod->mapped() : nullptr;
    const MappedMesh* mm = g ? &g->meshes[lod->mapped_index(m)] : nullptr;
    const PieceArrays a = g ? mapped_arrays(*g, *mm, buf)
                            : PieceArrays{bytes_of(m.positions), bytes_of(m.normals), nullptr, nullptr,
                                          bytes_of(m.objects), bytes_of(m.indices), m.positions.size(),
                                          m.indices.size()};
    const std::string what = (g ? g->path() : std::string("LOD data")) + ": LOD mesh " + std::to_string(p - M);
    auto color_of = [&](uint64_t v) {  // leaf LODs white (the object's colour), HLODs their objects'
      if (!a.objects) return 0xffffffffu;
      uint32_t o;
      std::memcpy(&o, a.objects + v * 4, 4);
      if (o >= scene.objects.size()) throw std::runtime_error(what + ": object " + std::to_string(o) + " out of range");
      return pack_rgba8(glm::vec4(glm::vec3(looks[o].color), 1.0f));
    };
    write_piece(a, color_of, out, uvs, false, what);
  };
  const uint64_t budget = upload.budget_bytes ? upload.budget_bytes : UINT64_MAX;  // 0: all of it
  pool = std::make_unique<GeometryPool>(gl_, budget, std::move(sizes), any_textured,
                                        std::move(loader));
  const bool fits = pool->total_bytes() <= pool->budget_bytes();
  if (fits) pool->preload();
  char buf[320];
  std::snprintf(buf, sizeof buf,
                "%s: geometry %s: %.1f MB in %zu pieces, budget %.1f MB (%s)", program_invocation_short_name,
                fits ? "resident" : "streams", pool->total_bytes() / 1e6, pool->pieces(),
                pool->budget_bytes() / 1e6,
                fits ? "all uploaded at start" : scene.mapped ? "read from the mapped caches as frames need it"
                                                               : "from the CPU copies as frames need it");
  std::fprintf(stderr, "%s\n", buf);
}

}  // namespace occ
