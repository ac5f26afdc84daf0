// Items sealed inside closed convex opaque solids (enclosure.hpp).
#include "common/cull/enclosure.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <optional>
#include <tuple>
#include <unordered_map>

#include "common/cull/culling.hpp"

namespace occ {
namespace {

struct LocalPlane {
  glm::dvec3 n;  // outward unit normal (mesh space)
  glm::dvec3 at; // a point of the plane
};

// The outward face planes of a closed, convex, opaque mesh seen from outside, or nothing.
std::optional<std::vector<LocalPlane>> solid_planes(const Scene& scene, uint32_t mesh_index) {
  const Mesh& m = scene.meshes[mesh_index];
  if (m.released || m.indices.empty() || m.indices.size() / 3 > Enclosures::kMaxSolidTriangles) return std::nullopt;
  const Material* mat = scene.material_of(mesh_index);
  if (mat && mat->alpha_mode != AlphaMode::Opaque) return std::nullopt;
  const bool double_sided = !mat || mat->double_sided;
  // Weld equal positions (vertices split by normals or texture coordinates).
  std::vector<uint32_t> order(m.positions.size()), weld(m.positions.size());
  for (uint32_t i = 0; i < order.size(); ++i) order[i] = i;
  auto less = [&](uint32_t a, uint32_t b) {
    const glm::vec3 &p = m.positions[a], &q = m.positions[b];
    return std::tie(p.x, p.y, p.z) < std::tie(q.x, q.y, q.z);
  };
  std::sort(order.begin(), order.end(), less);
  std::vector<glm::dvec3> unique;
  for (size_t i = 0; i < order.size(); ++i) {
    if (i == 0 || less(order[i - 1], order[i])) unique.push_back(glm::dvec3(m.positions[order[i]]));
    weld[order[i]] = uint32_t(unique.size() - 1);
  }
  // Closed and consistently wound: every directed edge once, and its reverse once.
  std::vector<std::pair<uint32_t, uint32_t>> edges;
  edges.reserve(m.indices.size());
  for (size_t t = 0; t + 2 < m.indices.size(); t += 3) {
    const uint32_t v[3] = {weld[m.indices[t]], weld[m.indices[t + 1]], weld[m.indices[t + 2]]};
    if (v[0] == v[1] || v[1] == v[2] || v[0] == v[2]) return std::nullopt;
    for (int e = 0; e < 3; ++e) edges.emplace_back(v[e], v[(e + 1) % 3]);
  }
  std::sort(edges.begin(), edges.end());
  if (std::adjacent_find(edges.begin(), edges.end()) != edges.end()) return std::nullopt;
  for (const auto& [a, b] : edges)
    if (!std::binary_search(edges.begin(), edges.end(), std::make_pair(b, a))) return std::nullopt;
  // Convex, all faces outward (or all inward, if double-sided: then flipped).
  glm::dvec3 centroid(0.0);
  Aabb box;
  for (const glm::dvec3& p : unique) {
    centroid += p;
    box.grow(p);
  }
  centroid /= double(unique.size());
  const double tol = 1e-6 * glm::length(box.extent());
  std::vector<LocalPlane> planes;
  int orientation = 0;
  for (size_t t = 0; t + 2 < m.indices.size(); t += 3) {
    const glm::dvec3 a = unique[weld[m.indices[t]]], b = unique[weld[m.indices[t + 1]]], c = unique[weld[m.indices[t + 2]]];
    glm::dvec3 n = glm::cross(b - a, c - a);
    const double len = glm::length(n);
    if (!(len > 0)) return std::nullopt;
    n /= len;
    const double side = glm::dot(n, a - centroid);
    const int o = side > tol ? 1 : side < -tol ? -1 : 0;
    if (o == 0 || (orientation != 0 && o != orientation)) return std::nullopt;
    orientation = o;
    if (o < 0) n = -n;
    for (const glm::dvec3& p : unique)
      if (glm::dot(n, p - a) > tol) return std::nullopt;
    planes.push_back({n, a});
  }
  if (orientation < 0 && !double_sided) return std::nullopt;  // front faces inwards: unseen from outside
  return planes;
}

// World boxes of objects, bucketed on a grid over the scene (the solids' candidates).
class BoxGrid {
 public:
  BoxGrid(const Aabb& bounds, const std::vector<std::pair<Aabb, uint32_t>>& boxes) : bounds_(bounds) {
    const double n = std::cbrt(double(std::max<size_t>(boxes.size(), 1)));
    for (int a = 0; a < 3; ++a) dims_[a] = std::clamp(int(n), 1, 64);
    cells_.resize(size_t(dims_[0]) * dims_[1] * dims_[2]);
    for (const auto& [box, id] : boxes) {
      const auto lo = cell(box.min), hi = cell(box.max);
      const size_t count = size_t(hi[0] - lo[0] + 1) * (hi[1] - lo[1] + 1) * (hi[2] - lo[2] + 1);
      if (count > 512) {
        big_.push_back(id);
        continue;
      }
      for (int x = lo[0]; x <= hi[0]; ++x)
        for (int y = lo[1]; y <= hi[1]; ++y)
          for (int z = lo[2]; z <= hi[2]; ++z) cells_[index({x, y, z})].push_back(id);
    }
  }
  // Candidates for a box around point p: those in its cell and the big ones.
  template <class F>
  void near(const glm::dvec3& p, F&& f) const {
    for (uint32_t id : cells_[index(cell(p))]) f(id);
    for (uint32_t id : big_) f(id);
  }

 private:
  std::array<int, 3> cell(const glm::dvec3& p) const {
    std::array<int, 3> c{};
    const glm::dvec3 e = bounds_.extent();
    for (int a = 0; a < 3; ++a) {
      const double t = e[a] > 0 ? (p[a] - bounds_.min[a]) / e[a] : 0.0;
      c[a] = std::clamp(int(std::floor(t * dims_[a])), 0, dims_[a] - 1);
    }
    return c;
  }
  size_t index(const std::array<int, 3>& c) const { return (size_t(c[2]) * dims_[1] + c[1]) * dims_[0] + c[0]; }
  Aabb bounds_;
  std::array<int, 3> dims_{1, 1, 1};
  std::vector<std::vector<uint32_t>> cells_;
  std::vector<uint32_t> big_;
};

bool strictly_inside(const Aabb& inner, const Aabb& outer) {
  return glm::all(glm::greaterThan(inner.min, outer.min)) && glm::all(glm::lessThan(inner.max, outer.max));
}

}  // namespace

Enclosures Enclosures::find(const Scene& scene, const Hierarchy& h) {
  Enclosures e;
  e.nodes_.assign(h.size(), Node{});
  // Candidates: objects of small meshes, with a transform that keeps orientation or double-sided.
  std::vector<std::pair<Aabb, uint32_t>> candidates;
  for (uint32_t o = 0; o < scene.objects.size(); ++o) {
    const Mesh& m = scene.meshes[scene.objects[o].mesh];
    if (m.released || m.indices.empty() || m.indices.size() / 3 > kMaxSolidTriangles) continue;
    candidates.emplace_back(m.box().transformed(scene.objects[o].transform), o);
  }
  if (candidates.empty()) return e;
  std::vector<Aabb> object_box(scene.objects.size());
  for (const auto& [box, o] : candidates) object_box[o] = box;
  const BoxGrid grid(scene.bounds(), candidates);
  std::unordered_map<uint32_t, std::optional<std::vector<LocalPlane>>> mesh_planes;
  std::unordered_map<uint32_t, std::vector<std::pair<glm::dvec3, double>>> world_planes;  // (n, d): n.p + d <= 0 inside
  auto planes_of = [&](uint32_t o) -> const std::vector<std::pair<glm::dvec3, double>>* {
    auto w = world_planes.find(o);
    if (w != world_planes.end()) return w->second.empty() ? nullptr : &w->second;
    const Object& obj = scene.objects[o];
    auto mp = mesh_planes.find(obj.mesh);
    if (mp == mesh_planes.end()) mp = mesh_planes.emplace(obj.mesh, solid_planes(scene, obj.mesh)).first;
    std::vector<std::pair<glm::dvec3, double>> out;
    const glm::dmat3 lin(obj.transform);
    const double det = glm::determinant(lin);
    const Material* mat = scene.material_of(obj.mesh);
    if (mp->second && det != 0 && (det > 0 || !mat || mat->double_sided)) {
      const glm::dmat3 normal = glm::transpose(glm::inverse(lin));
      for (const LocalPlane& p : *mp->second) {
        const glm::dvec3 n = glm::normalize(normal * p.n);
        out.emplace_back(n, -glm::dot(n, glm::dvec3(obj.transform * glm::dvec4(p.at, 1.0))));
      }
    }
    auto& stored = world_planes.emplace(o, std::move(out)).first->second;
    return stored.empty() ? nullptr : &stored;
  };
  // Items: the best solid sealing each.
  const auto& items = h.items();
  std::vector<double> item_margin(items.size(), 0.0);
  std::vector<Aabb> item_solid(items.size());
  std::vector<uint32_t> item_sealer(items.size(), kNoNode);
  std::vector<glm::dvec3> world;
  for (size_t i = 0; i < items.size(); ++i) {
    const Item& it = items[i];
    const Object& obj = scene.objects[it.object];
    const Mesh& m = scene.meshes[obj.mesh];
    if (m.released || it.cluster >= m.clusters.size()) continue;
    const MeshCluster& c = m.clusters[it.cluster];
    bool have_world = false;
    grid.near(it.box.center(), [&](uint32_t o) {
      if (o == it.object || !strictly_inside(it.box, object_box[o])) return;
      const auto* planes = planes_of(o);
      if (!planes) return;
      if (!have_world) {
        world.clear();
        for (uint32_t k = c.first_index; k < c.first_index + c.index_count; ++k)
          world.push_back(glm::dvec3(obj.transform * glm::dvec4(glm::dvec3(m.positions[m.indices[k]]), 1.0)));
        have_world = true;
      }
      double margin = std::numeric_limits<double>::infinity();
      for (const auto& [n, d] : *planes)
        for (const glm::dvec3& p : world) margin = std::min(margin, -(glm::dot(n, p) + d));
      // Strictly inside, by more than float rounding of the solid's own size.
      if (margin > 1e-4 * glm::length(object_box[o].extent()) && margin > item_margin[i]) {
        item_margin[i] = margin;
        item_solid[i] = object_box[o];
        item_sealer[i] = o;
      }
    });
    if (item_margin[i] > 0) ++e.sealed_items_;
  }
  std::sort(item_sealer.begin(), item_sealer.end());
  item_sealer.erase(std::unique(item_sealer.begin(), item_sealer.end()), item_sealer.end());
  e.solids_ = uint32_t(std::count_if(item_sealer.begin(), item_sealer.end(), [](uint32_t o) { return o != kNoNode; }));
  // Nodes, deepest first (ids are breadth-first: children after parents).
  for (size_t id = h.size(); id-- > 0;) {
    const HNode& n = h.node(uint32_t(id));
    Node& out = e.nodes_[id];
    if (n.item_count == 0) continue;
    double margin = std::numeric_limits<double>::infinity();
    if (n.leaf()) {
      for (uint32_t k = n.first_item; k < n.first_item + n.item_count; ++k) {
        margin = std::min(margin, item_margin[k]);
        out.solids.grow(item_solid[k]);
      }
    } else {
      for (uint32_t ch = n.first_child; ch < n.first_child + n.child_count; ++ch) {
        if (h.node(ch).item_count == 0) continue;
        margin = std::min(margin, e.nodes_[ch].margin);
        out.solids.grow(e.nodes_[ch].solids);
      }
    }
    out.margin = std::isfinite(margin) ? margin : 0.0;
  }
  return e;
}

bool Enclosures::hides(uint32_t id, const Camera& cam, double viewport_height_px) const {
  if (!sealed(id)) return false;
  const Node& n = nodes_[id];
  if (visible_without_query(n.solids, cam)) return false;  // the near plane may cut a solid
  if (!cam.sections.keeps_all(n.solids, cam.eye)) return false;  // a section plane may cut one open
  double far2 = 0;
  for (int i = 0; i < 8; ++i) {
    const glm::dvec3 c(i & 1 ? n.solids.max.x : n.solids.min.x, i & 2 ? n.solids.max.y : n.solids.min.y,
                       i & 4 ? n.solids.max.z : n.solids.min.z);
    far2 = std::max(far2, glm::dot(c - cam.eye, c - cam.eye));
  }
  const double pixel = 2.0 * std::tan(0.5 * cam.fovy_rad) / std::max(viewport_height_px, 1.0);
  return n.margin >= kMinMarginPixels * pixel * std::sqrt(far2);
}

}  // namespace occ
