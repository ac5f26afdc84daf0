#include "common/lod/lod_simplify.hpp"

#include <meshoptimizer.h>

#include <algorithm>
#include <cmath>
#include <unordered_map>

namespace occ {

LodMesh simplify_lod_mesh(const LodMesh& in, size_t target_indices) {
  LodMesh out;
  out.origin = in.origin;
  const size_t nv = in.positions.size();
  if (in.indices.empty() || nv == 0) {
    out = in;
    return out;
  }
  // Weld by position so that normal/colour seams do not block collapses.
  std::vector<uint32_t> remap(nv);
  const size_t nw = meshopt_generateVertexRemap(remap.data(), nullptr, nv, in.positions.data(), nv, sizeof(glm::vec3));
  std::vector<glm::vec3> wpos(nw);
  for (size_t v = 0; v < nv; ++v) wpos[remap[v]] = in.positions[v];
  std::vector<uint32_t> widx(in.indices.size());
  for (size_t i = 0; i < widx.size(); ++i) widx[i] = remap[in.indices[i]];
  // Candidates per welded vertex (CSR): the original vertices mapped to it.
  std::vector<uint32_t> cstart(nw + 1, 0), cand(nv);
  for (size_t v = 0; v < nv; ++v) ++cstart[remap[v] + 1];
  for (size_t w = 0; w < nw; ++w) cstart[w + 1] += cstart[w];
  {
    std::vector<uint32_t> fill(cstart.begin(), cstart.end() - 1);
    for (size_t v = 0; v < nv; ++v) cand[fill[remap[v]]++] = uint32_t(v);
  }

  const float scale = meshopt_simplifyScale(&wpos[0].x, nw, sizeof(glm::vec3));
  std::vector<uint32_t> dst(widx.size());
  float rel = 0;
  // Borders locked: open edges (cluster seams, the open bottom of a building) stay where they are,
  // so neighbouring clusters do not crack apart and walls are not lifted off the ground.
  size_t n = meshopt_simplify(dst.data(), widx.data(), widx.size(), &wpos[0].x, nw, sizeof(glm::vec3), target_indices,
                              1.0f, meshopt_SimplifyLockBorder, &rel);
  if (n > target_indices + target_indices / 2) {  // topology stopped it: try the sloppy simplifier
    std::vector<uint32_t> dst2(widx.size());
    float rel2 = 0;
    size_t n2 = meshopt_simplifySloppy(dst2.data(), widx.data(), widx.size(), &wpos[0].x, nw, sizeof(glm::vec3),
                                       target_indices, 1.0f, &rel2);
    if (n2 >= 3 && n2 < n) {
      dst.swap(dst2);
      n = n2;
      rel = rel2;
    }
  }
  dst.resize(n);
  double abs_err = double(rel) * double(scale);
  if (!std::isfinite(abs_err) || abs_err < 0) abs_err = double(scale);

  // Output vertices: (welded vertex, best-matching original vertex) pairs.
  std::unordered_map<uint64_t, uint32_t> made;
  made.reserve(n);
  out.indices.reserve(n);
  for (size_t t = 0; t + 2 < n; t += 3) {
    const glm::vec3 a = wpos[dst[t]], b = wpos[dst[t + 1]], c = wpos[dst[t + 2]];
    glm::vec3 fn = glm::cross(b - a, c - a);
    const float len = glm::length(fn);
    if (len > 0) fn /= len;
    for (int k = 0; k < 3; ++k) {
      const uint32_t w = dst[t + k];
      uint32_t best = cand[cstart[w]];
      float best_dot = -2;
      if (len > 0)
        for (uint32_t j = cstart[w]; j < cstart[w + 1]; ++j) {
          const float d = glm::dot(in.normals[cand[j]], fn);
          if (d > best_dot + 1e-6f) {
            best_dot = d;
            best = cand[j];
          }
        }
      const uint64_t key = uint64_t(w) << 32 | best;
      auto [it, fresh] = made.emplace(key, uint32_t(out.positions.size()));
      if (fresh) {
        out.positions.push_back(wpos[w]);
        out.normals.push_back(in.normals[best]);
        if (!in.objects.empty()) out.objects.push_back(in.objects[best]);
      }
      out.indices.push_back(it->second);
    }
  }
  // The simplifier's error is an estimate; never report less than how far the bounding box moved
  // (catches a part that vanished or shrank, which its quadrics may not see).
  Aabb before, after;
  for (uint32_t i : widx) before.grow(glm::dvec3(wpos[i]));
  for (size_t i = 0; i < n; ++i) after.grow(glm::dvec3(wpos[dst[i]]));
  double moved = before.diagonal();
  if (!after.empty()) {
    moved = 0;
    for (int a = 0; a < 3; ++a)
      moved = std::max({moved, std::abs(after.min[a] - before.min[a]), std::abs(after.max[a] - before.max[a])});
  }
  out.error = in.error + std::max(abs_err, moved);
  return out;
}

size_t simplify_target(size_t index_count, float ratio, uint32_t min_triangles) {
  size_t tris = size_t(double(index_count / 3) * ratio);
  return std::max<size_t>(tris, min_triangles) * 3;
}

}  // namespace occ
