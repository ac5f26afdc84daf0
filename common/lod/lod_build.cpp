// Builds the leaf LOD chains and the HLODs (lod_data.hpp); the simplifier is lod_simplify.cpp.
// A change to what it builds needs kCacheVersion (lod_cache.cpp) bumped.
#include "common/lod/lod_data.hpp"

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cstdio>
#include <exception>
#include <mutex>
#include <stdexcept>
#include <thread>
#include <unordered_map>

#include "common/lod/lod_simplify.hpp"
#include "common/progress.hpp"

namespace occ {

namespace {

// Largest axis scale of a transform's linear part (errors scale with it).
double max_scale(const glm::dmat4& m) {
  return std::max({glm::length(glm::dvec3(m[0])), glm::length(glm::dvec3(m[1])), glm::length(glm::dvec3(m[2]))});
}

// Runs work(k) for every k in [0, n) on two threads (the calling one and a helper; the target
// machines have two cores). work(k) must only write what belongs to k, so the result does not
// depend on the order. `report` runs on the calling thread after each of its own items. The first
// exception is rethrown after both threads stop.
template <class Work, class Report>
void for_each_on_two_threads(size_t n, const Work& work, const Report& report) {
  std::atomic<size_t> next{0};
  std::exception_ptr failure;
  std::mutex failure_mutex;
  auto run = [&](bool caller) {
    try {
      for (size_t k; (k = next.fetch_add(1)) < n;) {
        work(k);
        if (caller) report();
      }
    } catch (...) {
      next = n;
      std::lock_guard<std::mutex> lock(failure_mutex);
      if (!failure) failure = std::current_exception();
    }
  };
  std::thread helper;
  if (n > 1 && std::thread::hardware_concurrency() != 1) helper = std::thread(run, false);
  run(true);
  if (helper.joinable()) helper.join();
  if (failure) std::rethrow_exception(failure);
}

// The build's progress over `total` slots and HLODs, finished by both threads: a bar on a
// terminal, a plain line every 10 s in a log file (no terminal), so a long first build shows it is
// alive and how far it got. Silent when the label is empty.
class BuildProgress {
 public:
  BuildProgress(const std::string& label, size_t total) : label_(label), total_(total) {}
  void finished_one() { ++finished_; }  // any thread
  // On the calling thread only, after each of its items.
  void tick(const char* phase) {
    const size_t done = finished_.load();
    const double t = now_ms();
    if (!label_.empty() && !tty_ && t - last_line_ >= 10000 && done != total_) {
      last_line_ = t;
      const double frac = double(done) / double(std::max<size_t>(total_, 1));
      std::fprintf(stderr, "%s: building LODs: %zu/%zu nodes (%s, %.0f %%), %.0f s, ETA %.0f s\n", label_.c_str(),
                   done, total_, phase, 100.0 * frac, (t - t0_) / 1000.0,
                   frac > 0 ? (t - t0_) * (1 - frac) / frac / 1000.0 : 0.0);
    }
    if (label_.empty() || (t - last_print_ < 200 && done != total_)) return;
    last_print_ = t;
    const double frac = double(done) / double(std::max<size_t>(total_, 1));
    const double eta = frac > 0 ? (t - t0_) * (1 - frac) / frac / 1000.0 : 0;
    char bar[31];
    const int filled = int(frac * 30);
    for (int k = 0; k < 30; ++k) bar[k] = k < filled ? '#' : '.';
    bar[30] = 0;
    progress("%s: building LODs [%s] %zu/%zu nodes (%s) ETA %.0f s   ", label_.c_str(), bar, done, total_, phase, eta);
  }

 private:
  const std::string& label_;
  const size_t total_;
  std::atomic<size_t> finished_{0};
  const double t0_ = now_ms();
  double last_print_ = -1e9;
  double last_line_ = t0_;
  const bool tty_ = isatty(STDERR_FILENO);
};

// A distinct (mesh, cluster): its leaf LOD chain is built once for all its instances.
struct Slot {
  uint32_t mesh, cluster;
};

// The cluster's triangles as a compact mesh of only the vertices they use (missing normals: +z).
LodMesh compact_cluster(const Mesh& mesh, const MeshCluster& cl) {
  LodMesh base;
  std::unordered_map<uint32_t, uint32_t> local;
  for (uint32_t i = cl.first_index; i < cl.first_index + cl.index_count; ++i) {
    const uint32_t v = mesh.indices[i];
    auto [it, fresh] = local.emplace(v, uint32_t(base.positions.size()));
    if (fresh) {
      base.positions.push_back(mesh.positions[v]);
      base.normals.push_back(v < mesh.normals.size() ? mesh.normals[v] : glm::vec3(0, 0, 1));
    }
    base.indices.push_back(it->second);
  }
  return base;
}

// Appends m, moved to world by to_world, to merged (positions relative to merged.origin, normals
// by the inverse transpose); vertices without a source object get `object`.
void append_in_world(LodMesh& merged, const LodMesh& m, const glm::dmat4& to_world, uint32_t object) {
  const uint32_t base = uint32_t(merged.positions.size());
  const glm::dmat3 nm = glm::transpose(glm::inverse(glm::dmat3(to_world)));
  for (size_t v = 0; v < m.positions.size(); ++v) {
    const glm::dvec3 world = glm::dvec3(to_world * glm::dvec4(glm::dvec3(m.positions[v]), 1.0));
    merged.positions.push_back(glm::vec3(world - merged.origin));
    glm::dvec3 nrm = nm * glm::dvec3(m.normals[v]);
    const double len = glm::length(nrm);
    merged.normals.push_back(len > 0 ? glm::vec3(nrm / len) : glm::vec3(0, 0, 1));
    merged.objects.push_back(m.objects.empty() ? object : m.objects[v]);
  }
  for (uint32_t i : m.indices) merged.indices.push_back(base + i);
}

}  // namespace

// The build in its steps: slots, leaf LOD chains, leaf errors, HLODs bottom-up.
struct LodBuilder {
  static LodData run(const Scene& scene, const Hierarchy& h, const LodParams& p, const std::string& label) {
    LodData d;
    d.key_ = LodData::cache_key(h, p);
    const std::vector<Slot> slots = assign_slots(scene, h, d);
    uint32_t interior = 0;
    for (const HNode& n : h.nodes()) interior += !n.leaf() && n.item_count > 0;
    BuildProgress progress(label, slots.size() + interior);

    // Leaf LOD chains per slot, in mesh space (slots are independent: two threads).
    d.cluster_lods_.resize(slots.size() * kLeafLodLevels);
    for_each_on_two_threads(
        slots.size(),
        [&](size_t s) {
          build_leaf_chain(scene, slots[s], p, &d.cluster_lods_[s * kLeafLodLevels]);
          progress.finished_one();
        },
        [&] { progress.tick("leaf LODs"); });
    leaf_errors(scene, h, d);

    // Interior nodes level by level from the deepest: children first. The nodes of one level are
    // independent (each reads only its children's finished HLODs): two threads per level.
    const std::vector<std::vector<uint32_t>> levels = place_hlods(h, d);
    for (size_t level = levels.size(); level-- > 0;)
      for_each_on_two_threads(
          levels[level].size(),
          [&](size_t k) {
            build_hlod(scene, h, p, levels[level][k], d);
            progress.finished_one();
          },
          [&] { progress.tick("HLODs"); });
    progress_done();
    d.finish_hash();
    return d;
  }

 private:
  // The distinct (mesh, cluster) slots in item order; fills d.item_slot_.
  static std::vector<Slot> assign_slots(const Scene& scene, const Hierarchy& h, LodData& d) {
    const auto& items = h.items();
    std::unordered_map<uint64_t, uint32_t> slot_of;
    std::vector<Slot> slots;
    d.item_slot_.resize(items.size());
    for (size_t i = 0; i < items.size(); ++i) {
      const uint32_t mesh = scene.objects[items[i].object].mesh;
      const uint64_t key = uint64_t(mesh) << 32 | items[i].cluster;
      auto [it, fresh] = slot_of.emplace(key, uint32_t(slots.size()));
      if (fresh) slots.push_back({mesh, items[i].cluster});
      d.item_slot_[i] = it->second;
    }
    return slots;
  }

  // Levels 1..kLeafLodLevels of one slot into chain[0..kLeafLodLevels): each simplifies the one
  // before, never finer, errors monotone.
  static void build_leaf_chain(const Scene& scene, Slot slot, const LodParams& p, LodMesh* chain) {
    const Mesh& mesh = scene.meshes[slot.mesh];
    const LodMesh base = compact_cluster(mesh, mesh.clusters[slot.cluster]);
    const LodMesh* prev = &base;
    for (uint32_t l = 1; l <= kLeafLodLevels; ++l) {
      LodMesh& dst = chain[l - 1];
      const size_t target = simplify_target(prev->indices.size(), p.level_ratio, p.min_triangles);
      if (target < prev->indices.size())
        dst = simplify_lod_mesh(*prev, target);
      else
        dst = *prev;
      if (dst.indices.size() > prev->indices.size()) dst = *prev;  // never finer
      dst.error = std::max(dst.error, prev->error);
      prev = &dst;
    }
  }

  // Errors of the leaves in world units (max over their items, scaled by each object's largest
  // axis scale, monotone over levels); sizes d.errors_ and d.hlod_of_node_ for every node.
  static void leaf_errors(const Scene& scene, const Hierarchy& h, LodData& d) {
    const auto& items = h.items();
    const size_t N = h.size();
    d.errors_.assign(N, {0, 0, 0, 0});
    d.hlod_of_node_.assign(N, kNoNode);
    for (uint32_t id = 0; id < N; ++id) {
      const HNode& n = h.node(id);
      if (!n.leaf() || n.item_count == 0) continue;
      for (uint32_t i = n.first_item; i < n.first_item + n.item_count; ++i) {
        const double s = max_scale(scene.objects[items[i].object].transform);
        for (uint32_t l = 1; l <= kLeafLodLevels; ++l)
          d.errors_[id][l] = std::max(d.errors_[id][l], d.item_lod(i, l).error * s);
      }
      for (uint32_t l = 1; l <= kLeafLodLevels; ++l)
        d.errors_[id][l] = std::max(d.errors_[id][l], d.errors_[id][l - 1]);
    }
  }

  // One HLOD per non-empty interior node, numbered in id order (d.hlods_, d.hlod_of_node_); returns
  // those nodes grouped by depth.
  static std::vector<std::vector<uint32_t>> place_hlods(const Hierarchy& h, LodData& d) {
    std::vector<uint32_t> order;
    for (uint32_t id = 0; id < h.size(); ++id)
      if (!h.node(id).leaf() && h.node(id).item_count > 0) order.push_back(id);
    d.hlods_.resize(order.size());
    for (size_t k = 0; k < order.size(); ++k) d.hlod_of_node_[order[k]] = uint32_t(k);
    std::vector<std::vector<uint32_t>> levels(h.depth());
    for (uint32_t id : order) levels[h.node(id).depth].push_back(id);
    return levels;
  }

  // The HLOD of interior node id: its children's coarsest representations (leaf level 3 or child
  // HLOD) merged around the node's box centre and simplified; error = children's + its own.
  static void build_hlod(const Scene& scene, const Hierarchy& h, const LodParams& p, uint32_t id, LodData& d) {
    const auto& items = h.items();
    const HNode& n = h.node(id);
    LodMesh merged;
    merged.origin = n.box.center();
    double child_err = 0;
    for (uint32_t c = n.first_child; c < n.first_child + n.child_count; ++c) {
      const HNode& cn = h.node(c);
      if (cn.item_count == 0) continue;
      child_err = std::max(child_err, d.errors_[c][kLeafLodLevels]);
      if (cn.leaf()) {
        for (uint32_t i = cn.first_item; i < cn.first_item + cn.item_count; ++i)
          append_in_world(merged, d.item_lod(i, kLeafLodLevels), scene.objects[items[i].object].transform,
                          items[i].object);
      } else {
        const LodMesh& ch = d.hlods_[d.hlod_of_node_[c]];
        glm::dmat4 shift(1.0);
        shift[3] = glm::dvec4(ch.origin, 1.0);
        append_in_world(merged, ch, shift, 0);
      }
    }
    merged.error = 0;
    const size_t target = simplify_target(merged.indices.size(), p.hlod_ratio, p.min_triangles);
    LodMesh& out = d.hlods_[d.hlod_of_node_[id]];
    out = target < merged.indices.size() ? simplify_lod_mesh(merged, target) : merged;
    out.error += child_err;  // children's error + this simplification's: monotone
    out.error = std::max(out.error, child_err);
    d.errors_[id].fill(out.error);
  }
};

LodData LodData::build(const Scene& scene, const Hierarchy& h, const LodParams& params, const std::string& label) {
  return LodBuilder::run(scene, h, params, label);
}

uint64_t LodData::bytes() const {
  uint64_t b = 0;
  auto mesh = [&](const LodMesh& m) {
    b += m.positions.size() * 24 + m.objects.size() * 4 + m.indices.size() * 4 + sizeof(LodMesh);
  };
  for (const auto& m : cluster_lods_) mesh(m);
  for (const auto& m : hlods_) mesh(m);
  return b + item_slot_.size() * 4 + hlod_of_node_.size() * 4 + errors_.size() * sizeof(errors_[0]);
}

void LodMesh::release_geometry() {
  if (released) return;
  released_triangles = indices.size() / 3;
  released_vertices = positions.size();
  released = true;
  std::vector<glm::vec3>().swap(positions);
  std::vector<glm::vec3>().swap(normals);
  std::vector<uint32_t>().swap(objects);
  std::vector<uint32_t>().swap(indices);
}

void LodData::release(const LodMesh& m) {
  auto owns = [&](const std::vector<LodMesh>& v) { return !v.empty() && &m >= v.data() && &m < v.data() + v.size(); };
  if (owns(cluster_lods_))
    cluster_lods_[size_t(&m - cluster_lods_.data())].release_geometry();
  else if (owns(hlods_))
    hlods_[size_t(&m - hlods_.data())].release_geometry();
  else
    throw std::logic_error("LodData::release: not one of this LodData's meshes");
}

size_t LodData::mapped_index(const LodMesh& m) const {
  if (!cluster_lods_.empty() && &m >= cluster_lods_.data() && &m < cluster_lods_.data() + cluster_lods_.size())
    return size_t(&m - cluster_lods_.data());
  return cluster_lods_.size() + size_t(&m - hlods_.data());
}

bool LodData::geometry_released() const {
  auto any = [](const std::vector<LodMesh>& v) {
    return std::any_of(v.begin(), v.end(), [](const LodMesh& m) { return m.released; });
  };
  return any(cluster_lods_) || any(hlods_);
}

uint64_t LodData::total_triangles() const {
  uint64_t t = 0;
  for (const auto& m : cluster_lods_) t += m.triangles();
  for (const auto& m : hlods_) t += m.triangles();
  return t;
}

}  // namespace occ
