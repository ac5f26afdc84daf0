#include "common/lod.hpp"

#include <meshoptimizer.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <unordered_map>

#include "common/hash.hpp"
#include "common/progress.hpp"

namespace occ {

namespace {

constexpr uint32_t kCacheVersion = 2;  // bump whenever the builder changes its output
constexpr char kCacheMagic[8] = {'O', 'C', 'C', 'L', 'O', 'D', '\r', '\n'};

double now_ms() {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

// Largest axis scale of a transform's linear part (errors scale with it).
double max_scale(const glm::dmat4& m) {
  return std::max({glm::length(glm::dvec3(m[0])), glm::length(glm::dvec3(m[1])), glm::length(glm::dvec3(m[2]))});
}

// Simplifies `in` towards target_indices (a multiple of 3). Returns the new mesh (same origin)
// with error = in.error + the simplifier's absolute error.
LodMesh simplify(const LodMesh& in, size_t target_indices) {
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

size_t target_for(size_t index_count, float ratio, uint32_t min_triangles) {
  size_t tris = size_t(double(index_count / 3) * ratio);
  return std::max<size_t>(tris, min_triangles) * 3;
}

}  // namespace

struct LodBuilder {
  static LodData run(const Scene& scene, const Hierarchy& h, const LodParams& p, const std::string& label) {
    LodData d;
    d.key_ = LodData::cache_key(h, p);
    const auto& items = h.items();
    // Distinct (mesh, cluster) slots.
    std::unordered_map<uint64_t, uint32_t> slot_of;
    std::vector<std::pair<uint32_t, uint32_t>> slots;
    d.item_slot_.resize(items.size());
    for (size_t i = 0; i < items.size(); ++i) {
      const uint32_t mesh = scene.objects[items[i].object].mesh;
      const uint64_t key = uint64_t(mesh) << 32 | items[i].cluster;
      auto [it, fresh] = slot_of.emplace(key, uint32_t(slots.size()));
      if (fresh) slots.emplace_back(mesh, items[i].cluster);
      d.item_slot_[i] = it->second;
    }
    uint32_t interior = 0;
    for (const HNode& n : h.nodes()) interior += !n.leaf() && n.item_count > 0;
    const size_t total = slots.size() + interior;
    size_t done = 0;
    const double t0 = now_ms();
    double last_print = -1e9;
    auto tick = [&](const char* phase) {
      ++done;
      const double t = now_ms();
      if (label.empty() || (t - last_print < 200 && done != total)) return;
      last_print = t;
      const double frac = double(done) / double(std::max<size_t>(total, 1));
      const double eta = frac > 0 ? (t - t0) * (1 - frac) / frac / 1000.0 : 0;
      char bar[31];
      const int filled = int(frac * 30);
      for (int k = 0; k < 30; ++k) bar[k] = k < filled ? '#' : '.';
      bar[30] = 0;
      progress("%s: building LODs [%s] %zu/%zu nodes (%s) ETA %.0f s   ", label.c_str(), bar, done, total, phase, eta);
    };

    // Leaf LOD chains per slot, in mesh space.
    d.cluster_lods_.resize(slots.size() * kLeafLodLevels);
    for (size_t s = 0; s < slots.size(); ++s) {
      const Mesh& mesh = scene.meshes[slots[s].first];
      const MeshCluster& cl = mesh.clusters[slots[s].second];
      LodMesh base;  // the cluster, compacted
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
      const LodMesh* prev = &base;
      for (uint32_t l = 1; l <= kLeafLodLevels; ++l) {
        LodMesh& dst = d.cluster_lods_[s * kLeafLodLevels + l - 1];
        const size_t target = target_for(prev->indices.size(), p.level_ratio, p.min_triangles);
        if (target < prev->indices.size())
          dst = simplify(*prev, target);
        else
          dst = *prev;
        if (dst.indices.size() > prev->indices.size()) dst = *prev;  // never finer
        dst.error = std::max(dst.error, prev->error);
        prev = &dst;
      }
      tick("leaf LODs");
    }

    // Errors of leaves (world units), HLODs bottom-up (children have larger ids).
    const size_t N = h.size();
    d.errors_.assign(N, {0, 0, 0, 0});
    d.hlod_of_node_.assign(N, kNoNode);
    std::vector<uint32_t> hlod_index(N, kNoNode);
    for (uint32_t id = 0; id < N; ++id) {
      const HNode& n = h.node(id);
      if (!n.leaf() || n.item_count == 0) continue;
      for (uint32_t i = n.first_item; i < n.first_item + n.item_count; ++i) {
        const double s = max_scale(scene.objects[items[i].object].transform);
        for (uint32_t l = 1; l <= kLeafLodLevels; ++l)
          d.errors_[id][l] = std::max(d.errors_[id][l], d.item_lod(i, l).error * s);
      }
      for (uint32_t l = 1; l <= kLeafLodLevels; ++l) d.errors_[id][l] = std::max(d.errors_[id][l], d.errors_[id][l - 1]);
    }
    // Interior nodes in decreasing id order: children first.
    std::vector<uint32_t> order;
    for (uint32_t id = 0; id < N; ++id)
      if (!h.node(id).leaf() && h.node(id).item_count > 0) order.push_back(id);
    d.hlods_.resize(order.size());
    for (size_t k = 0; k < order.size(); ++k) d.hlod_of_node_[order[k]] = uint32_t(k);
    for (size_t k = order.size(); k-- > 0;) {
      const uint32_t id = order[k];
      const HNode& n = h.node(id);
      LodMesh merged;
      merged.origin = n.box.center();
      double child_err = 0;
      auto append = [&](const LodMesh& m, const glm::dmat4& to_world, uint32_t object) {
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
      };
      for (uint32_t c = n.first_child; c < n.first_child + n.child_count; ++c) {
        const HNode& cn = h.node(c);
        if (cn.item_count == 0) continue;
        child_err = std::max(child_err, d.errors_[c][kLeafLodLevels]);
        if (cn.leaf()) {
          for (uint32_t i = cn.first_item; i < cn.first_item + cn.item_count; ++i)
            append(d.item_lod(i, kLeafLodLevels), scene.objects[items[i].object].transform, items[i].object);
        } else {
          const LodMesh& ch = d.hlods_[d.hlod_of_node_[c]];
          glm::dmat4 shift(1.0);
          shift[3] = glm::dvec4(ch.origin, 1.0);
          append(ch, shift, 0);
        }
      }
      merged.error = 0;
      const size_t target = target_for(merged.indices.size(), p.hlod_ratio, p.min_triangles);
      LodMesh& out = d.hlods_[d.hlod_of_node_[id]];
      out = target < merged.indices.size() ? simplify(merged, target) : merged;
      out.error += child_err;  // children's error + this simplification's: monotone
      out.error = std::max(out.error, child_err);
      d.errors_[id].fill(out.error);
      tick("HLODs");
    }
    progress_done();
    d.finish_hash();
    return d;
  }
};

LodData LodData::build(const Scene& scene, const Hierarchy& h, const LodParams& params, const std::string& label) {
  return LodBuilder::run(scene, h, params, label);
}

uint64_t LodData::cache_key(const Hierarchy& h, const LodParams& p) {
  Hasher k;
  k.u32(kCacheVersion);
  k.u64(h.fingerprint());
  k.f32(p.level_ratio);
  k.f32(p.hlod_ratio);
  k.u32(p.min_triangles);
  k.u32(kLeafLodLevels);
  return k.value();
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

uint64_t LodData::total_triangles() const {
  uint64_t t = 0;
  for (const auto& m : cluster_lods_) t += m.triangles();
  for (const auto& m : hlods_) t += m.triangles();
  return t;
}

// ---- Serialisation: header (magic, version, key, payload bytes, payload hash) + payload.

namespace {

class Writer {
 public:
  std::vector<uint8_t> buf;
  template <class T>
  void pod(const T& v) {
    const auto* p = reinterpret_cast<const uint8_t*>(&v);
    buf.insert(buf.end(), p, p + sizeof(T));
  }
  template <class T>
  void vec(const std::vector<T>& v) {
    pod(uint64_t(v.size()));
    const auto* p = reinterpret_cast<const uint8_t*>(v.data());
    buf.insert(buf.end(), p, p + v.size() * sizeof(T));
  }
};

class Reader {
 public:
  Reader(const uint8_t* p, size_t n) : p_(p), n_(n) {}
  template <class T>
  bool pod(T& v) {
    if (n_ - off_ < sizeof(T)) return false;
    std::memcpy(&v, p_ + off_, sizeof(T));
    off_ += sizeof(T);
    return true;
  }
  template <class T>
  bool vec(std::vector<T>& v) {
    uint64_t count = 0;
    if (!pod(count)) return false;
    if (count > (n_ - off_) / sizeof(T)) return false;  // checked before allocating
    v.resize(count);
    if (count > 0) std::memcpy(v.data(), p_ + off_, count * sizeof(T));
    off_ += count * sizeof(T);
    return true;
  }
  bool done() const { return off_ == n_; }

 private:
  const uint8_t* p_;
  size_t n_, off_ = 0;
};

void write_mesh(Writer& w, const LodMesh& m) {
  w.pod(m.origin.x);
  w.pod(m.origin.y);
  w.pod(m.origin.z);
  w.pod(m.error);
  w.vec(m.positions);
  w.vec(m.normals);
  w.vec(m.objects);
  w.vec(m.indices);
}

bool read_mesh(Reader& r, LodMesh& m, size_t object_count) {
  if (!r.pod(m.origin.x) || !r.pod(m.origin.y) || !r.pod(m.origin.z) || !r.pod(m.error)) return false;
  if (!r.vec(m.positions) || !r.vec(m.normals) || !r.vec(m.objects) || !r.vec(m.indices)) return false;
  if (m.normals.size() != m.positions.size()) return false;
  if (!m.objects.empty() && m.objects.size() != m.positions.size()) return false;
  if (m.indices.size() % 3 != 0 || !std::isfinite(m.error) || m.error < 0) return false;
  for (uint32_t i : m.indices)
    if (i >= m.positions.size()) return false;
  for (uint32_t o : m.objects)
    if (o >= object_count) return false;
  return true;
}

uint64_t payload_hash(const std::vector<uint8_t>& p) {
  Hasher h;
  h.bytes(p.data(), p.size());
  return h.value();
}

std::vector<uint8_t> serialize(const std::vector<LodMesh>& clusters, const std::vector<uint32_t>& slots,
                               const std::vector<LodMesh>& hlods, const std::vector<uint32_t>& hlod_of_node,
                               const std::vector<std::array<double, kLeafLodLevels + 1>>& errors) {
  Writer w;
  w.pod(uint64_t(clusters.size()));
  for (const auto& m : clusters) write_mesh(w, m);
  w.vec(slots);
  w.pod(uint64_t(hlods.size()));
  for (const auto& m : hlods) write_mesh(w, m);
  w.vec(hlod_of_node);
  w.vec(errors);
  return std::move(w.buf);
}

}  // namespace

void LodData::finish_hash() {
  hash_ = payload_hash(serialize(cluster_lods_, item_slot_, hlods_, hlod_of_node_, errors_));
}

std::optional<std::string> LodData::save(const std::string& path) const {
  std::vector<uint8_t> payload = serialize(cluster_lods_, item_slot_, hlods_, hlod_of_node_, errors_);
  Writer head;
  head.buf.insert(head.buf.end(), kCacheMagic, kCacheMagic + 8);
  head.pod(kCacheVersion);
  head.pod(key_);
  head.pod(uint64_t(payload.size()));
  head.pod(payload_hash(payload));
  std::error_code ec;
  std::filesystem::path p(path);
  if (p.has_parent_path()) std::filesystem::create_directories(p.parent_path(), ec);
  const std::string tmp = path + ".tmp." + std::to_string(::getpid());
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out) return "cannot write " + tmp;
    out.write(reinterpret_cast<const char*>(head.buf.data()), std::streamsize(head.buf.size()));
    out.write(reinterpret_cast<const char*>(payload.data()), std::streamsize(payload.size()));
    if (!out) {
      std::filesystem::remove(tmp, ec);
      return "cannot write " + tmp + " (disk full?)";
    }
  }
  std::filesystem::rename(tmp, path, ec);
  if (ec) {
    std::filesystem::remove(tmp, ec);
    return "cannot rename " + tmp + " to " + path;
  }
  return std::nullopt;
}

std::optional<LodData> LodData::load(const std::string& path, uint64_t expected_key, const Scene& scene,
                                     const Hierarchy& h, std::string* why) {
  auto fail = [&](const std::string& w) -> std::optional<LodData> {
    if (why) *why = w;
    return std::nullopt;
  };
  std::ifstream in(path, std::ios::binary);
  if (!in) return fail("missing");
  std::vector<uint8_t> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  constexpr size_t kHead = 8 + 4 + 8 + 8 + 8;
  if (bytes.size() < kHead) return fail("truncated header (" + std::to_string(bytes.size()) + " bytes)");
  if (std::memcmp(bytes.data(), kCacheMagic, 8) != 0) return fail("bad magic (not an occswitch LOD cache)");
  Reader head(bytes.data() + 8, kHead - 8);
  uint32_t version = 0;
  uint64_t key = 0, size = 0, hash = 0;
  head.pod(version);
  head.pod(key);
  head.pod(size);
  head.pod(hash);
  if (version != kCacheVersion)
    return fail("format version " + std::to_string(version) + ", expected " + std::to_string(kCacheVersion));
  if (key != expected_key) return fail("stale (built for another scene, hierarchy or LOD parameters)");
  if (size != bytes.size() - kHead)
    return fail("truncated or padded payload (" + std::to_string(bytes.size() - kHead) + " bytes, header says " +
                std::to_string(size) + ")");
  std::vector<uint8_t> payload(bytes.begin() + kHead, bytes.end());
  if (payload_hash(payload) != hash) return fail("checksum mismatch (corrupt)");
  LodData d;
  d.key_ = key;
  Reader r(payload.data(), payload.size());
  uint64_t nc = 0, nh = 0;
  if (!r.pod(nc) || nc > payload.size()) return fail("corrupt cluster LOD count");
  d.cluster_lods_.resize(nc);
  for (auto& m : d.cluster_lods_)
    if (!read_mesh(r, m, scene.objects.size())) return fail("corrupt cluster LOD mesh");
  if (!r.vec(d.item_slot_) || d.item_slot_.size() != h.items().size()) return fail("corrupt item table");
  for (uint32_t s : d.item_slot_)
    if (uint64_t(s + 1) * kLeafLodLevels > nc) return fail("item slot out of range");
  if (!r.pod(nh) || nh > payload.size()) return fail("corrupt HLOD count");
  d.hlods_.resize(nh);
  for (auto& m : d.hlods_)
    if (!read_mesh(r, m, scene.objects.size())) return fail("corrupt HLOD mesh");
  if (!r.vec(d.hlod_of_node_) || d.hlod_of_node_.size() != h.size()) return fail("corrupt node table");
  for (uint32_t x : d.hlod_of_node_)
    if (x != kNoNode && x >= nh) return fail("HLOD index out of range");
  if (!r.vec(d.errors_) || d.errors_.size() != h.size()) return fail("corrupt error table");
  for (uint32_t id = 0; id < h.size(); ++id) {
    const HNode& n = h.node(id);
    if ((!n.leaf() && n.item_count > 0) != (d.hlod_of_node_[id] != kNoNode)) return fail("HLOD table inconsistent");
    for (double e : d.errors_[id])
      if (!std::isfinite(e) || e < 0) return fail("bad error value");
  }
  if (!r.done()) return fail("trailing bytes");
  d.hash_ = hash;
  return d;
}

std::string lod_cache_path(const std::string& cache_dir, const std::string& spec) {
  std::string dir = cache_dir;
  if (dir.empty()) {
    if (const char* x = std::getenv("XDG_CACHE_HOME"); x && *x)
      dir = std::string(x) + "/occswitch";
    else if (const char* home = std::getenv("HOME"); home && *home)
      dir = std::string(home) + "/.cache/occswitch";
    else
      dir = "/tmp/occswitch";
  }
  std::string name = std::filesystem::path(spec).filename().string();
  for (char& c : name)
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '.' && c != '-' && c != '_') c = '_';
  if (name.size() > 48) name.resize(48);
  Hasher hs;
  hs.str(spec);
  char hex[17];
  std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(hs.value()));
  return dir + "/" + name + "-" + std::string(hex, 8) + ".lod";
}

namespace {
long rss_kb(const char* field) {
  std::ifstream s("/proc/self/status");
  std::string line;
  while (std::getline(s, line))
    if (line.rfind(field, 0) == 0) return std::atol(line.c_str() + std::strlen(field));
  return 0;
}
}  // namespace

LodData load_or_build_lod(const Scene& scene, const Hierarchy& h, const LodParams& params, const std::string& cache_dir,
                          const std::string& spec, const std::string& who) {
  const std::string path = lod_cache_path(cache_dir, spec);
  const uint64_t key = LodData::cache_key(h, params);
  const double t0 = now_ms();
  std::string why;
  std::optional<LodData> cached = LodData::load(path, key, scene, h, &why);
  char buf[512];
  if (cached) {
    std::snprintf(buf, sizeof buf, "%s: LOD cache %s: %zu HLODs, %.3f M LOD triangles, %.1f MB (loaded in %.0f ms)",
                  who.c_str(), path.c_str(), cached->hlods().size(), cached->total_triangles() / 1e6,
                  cached->bytes() / 1e6, now_ms() - t0);
    std::cerr << buf << "\n";
    return std::move(*cached);
  }
  if (why != "missing") std::cerr << who << ": LOD cache " << path << " is unusable (" << why << "): rebuilding\n";
  const long rss0 = rss_kb("VmRSS:");
  LodData d = LodData::build(scene, h, params, who);
  const double ms = now_ms() - t0;
  const long peak = rss_kb("VmHWM:");
  std::snprintf(buf, sizeof buf,
                "%s: built LODs in %.1f s: %zu cluster LODs, %zu HLODs, %.3f M LOD triangles, %.1f MB of LOD data, "
                "RSS %+.1f MB (peak %.1f MB)",
                who.c_str(), ms / 1000.0, d.cluster_lods().size(), d.hlods().size(), d.total_triangles() / 1e6,
                d.bytes() / 1e6, (rss_kb("VmRSS:") - rss0) / 1024.0, peak / 1024.0);
  std::cerr << buf << "\n";
  if (auto err = d.save(path))
    std::cerr << who << ": warning: LOD cache not written: " << *err << "\n";
  return d;
}

// ---- Renderables and selection.

Renderables::Renderables(const Hierarchy& h, const LodData* lod) : h_(h), lod_(lod), n_(uint32_t(h.size())) {
  leaf_index_.assign(h.size(), kNoNode);
  for (uint32_t id = 0; id < h.size(); ++id)
    if (h.node(id).leaf()) {
      leaf_index_[id] = uint32_t(extra_leaf_.size());
      extra_leaf_.push_back(id);
    }
  count_ = n_ + uint32_t(extra_leaf_.size()) * kLeafLodLevels;
}

uint64_t Renderables::triangles(uint32_t r) const {
  const uint32_t node = node_of(r), level = level_of(r);
  const HNode& n = h_.node(node);
  if (n.leaf()) {
    if (level == 0 || !lod_) return n.triangles;
    uint64_t t = 0;
    for (uint32_t i = n.first_item; i < n.first_item + n.item_count; ++i) t += lod_->item_lod(i, level).triangles();
    return t;
  }
  const LodMesh* m = lod_ ? lod_->hlod(node) : nullptr;
  return m ? m->triangles() : n.triangles;
}

LodBenefit lod_benefit(const LodData& lod, const Hierarchy& h) {
  Renderables r(h, &lod);
  uint64_t full = 0, leaves_coarse = 0;
  for (uint32_t id = 0; id < h.size(); ++id)
    if (h.node(id).leaf()) {
      full += h.node(id).triangles;
      leaves_coarse += r.triangles(r.id(id, kLeafLodLevels));
    }
  if (full == 0) return {};
  uint64_t below_root = 0;
  const HNode& root = h.node(0);
  if (root.leaf()) {
    below_root = leaves_coarse;
  } else {
    for (uint32_t c = root.first_child; c < root.first_child + root.child_count; ++c)
      below_root += h.node(c).leaf() ? r.triangles(r.id(c, kLeafLodLevels)) : r.triangles(c);
  }
  const uint64_t coarse = std::min({leaves_coarse, below_root, full});
  return {1.0 - double(coarse) / double(full), full - coarse};
}

double projected_error_px(double object_error, double distance, double viewport_height_px, double fovy_rad) {
  if (!(distance > 0)) return std::numeric_limits<double>::infinity();  // eye in or on the box
  if (!(object_error > 0)) return 0.0;
  const double t = std::tan(0.5 * fovy_rad);
  if (!(t > 0)) return std::numeric_limits<double>::infinity();
  return object_error * viewport_height_px / (2.0 * distance * t);
}

LodSelector::LodSelector(const Renderables& r, const Camera& cam, double viewport_height_px, double tau)
    : r_(r), h_(r.hierarchy()), cam_(cam), tau_(tau) {
  scale_ = viewport_height_px;
}

double LodSelector::error_px(uint32_t node, uint32_t level) const {
  if (!r_.lod()) return std::numeric_limits<double>::infinity();
  const double d = std::sqrt(h_.node(node).box.distance2(cam_.eye));
  return projected_error_px(r_.lod()->error(node, level), d, scale_, cam_.fovy_rad);
}

bool LodSelector::satisfies(uint32_t node) const {
  const HNode& n = h_.node(node);
  if (n.leaf()) return true;
  if (!(tau_ > 0) || !r_.lod() || n.item_count == 0) return false;
  return error_px(node, 0) <= tau_;
}

uint32_t LodSelector::leaf_level(uint32_t node) const {
  if (!(tau_ > 0) || !r_.lod()) return 0;
  for (uint32_t l = kLeafLodLevels; l >= 1; --l)
    if (error_px(node, l) <= tau_) return l;
  return 0;
}

uint32_t LodSelector::renderable(uint32_t node) const {
  return h_.node(node).leaf() ? r_.id(node, leaf_level(node)) : node;
}

uint32_t LodSelector::coarsest(uint32_t node) const {
  if (!(tau_ > 0) || !r_.lod()) return h_.node(node).leaf() ? node : node;
  return h_.node(node).leaf() ? r_.id(node, kLeafLodLevels) : node;
}

}  // namespace occ
