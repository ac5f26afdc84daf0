// The binary LOD cache: LodData::cache_key/save/load, the data hash and load_or_build_lod
// (lod_cache.hpp).
#include "common/lod/lod_cache.hpp"

#include <signal.h>
#include <unistd.h>

#include <cctype>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <vector>

#include "common/hash.hpp"
#include "common/mapped_file.hpp"
#include "common/progress.hpp"

namespace occ {

// ---- Serialisation: header (magic, version, key, payload bytes, payload hash) + payload.

namespace {

// Bump whenever the builder (lod_build.cpp, lod_simplify.cpp) changes its output.
constexpr uint32_t kCacheVersion = 3;  // 3: the structure ahead of the arrays
constexpr char kCacheMagic[8] = {'O', 'C', 'C', 'L', 'O', 'D', '\r', '\n'};

// Writes the payload in pieces to a sink (put(data, bytes)): counted, hashed or written to the
// file as it goes, never the whole payload in memory (1.9 GB at plant:80).
template <class Put>
class Writer {
 public:
  explicit Writer(Put& put) : put_(put) {}
  template <class T>
  void pod(const T& v) {
    put_(&v, sizeof(T));
  }
  template <class T>
  void vec(const std::vector<T>& v) {
    pod(uint64_t(v.size()));
    raw(v);
  }
  template <class T>
  void raw(const std::vector<T>& v) {  // the elements only (their count is elsewhere)
    if (!v.empty()) put_(v.data(), v.size() * sizeof(T));
  }

 private:
  Put& put_;
};

// Hasher::bytes of a stream whose total size is known in advance: the same value as hashing the
// whole payload at once (LodData::hash(), the load's check).
class StreamBytesHash {
 public:
  explicit StreamBytesHash(uint64_t total) { h_.u64(total); }
  void operator()(const void* data, size_t n) {
    const auto* p = static_cast<const uint8_t*>(data);
    while (n > 0) {
      const size_t k = std::min<size_t>(8 - fill_, n);
      std::memcpy(carry_ + fill_, p, k);
      fill_ += k, p += k, n -= k;
      if (fill_ == 8) {
        uint64_t w;
        std::memcpy(&w, carry_, 8);
        h_.u64(w);
        fill_ = 0;
      }
    }
  }
  uint64_t value() const {
    Hasher h = h_;
    uint64_t tail = 0;
    std::memcpy(&tail, carry_, fill_);
    h.u64(tail);
    return h.value();
  }

 private:
  Hasher h_;
  uint8_t carry_[8] = {};
  size_t fill_ = 0;
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
  // The count of an array stored in the array section: checked against the bytes left.
  bool count(MappedArray& a, size_t elem_bytes) {
    if (!pod(a.count) || a.count > (n_ - off_) / elem_bytes) return false;
    a.bytes = a.count * elem_bytes;
    return true;
  }
  size_t offset() const { return off_; }

 private:
  const uint8_t* p_;
  size_t n_, off_ = 0;
};

// A mesh's arrays in the order the structure counts them and the array section stores them,
// each with its place in the file: f(array, place).
template <class M, class P, class F>
void mesh_arrays(M& m, P& place, const F& f) {
  f(m.positions, place.positions), f(m.normals, place.normals), f(m.objects, place.objects),
      f(m.indices, place.indices);
}

// A mesh's record in the structure: origin, error and the counts of its arrays.
template <class W>
void write_mesh_record(W& w, const LodMesh& m) {
  w.pod(m.origin.x);
  w.pod(m.origin.y);
  w.pod(m.origin.z);
  w.pod(m.error);
  MappedMesh unused;
  mesh_arrays(m, unused, [&](const auto& a, const MappedArray&) { w.pod(uint64_t(a.size())); });
}

bool read_mesh_record(Reader& r, LodMesh& m, MappedMesh& place) {
  if (!r.pod(m.origin.x) || !r.pod(m.origin.y) || !r.pod(m.origin.z) || !r.pod(m.error)) return false;
  bool ok = true;
  mesh_arrays(m, place, [&](const auto& a, MappedArray& p) { ok = ok && r.count(p, sizeof(a[0])); });
  const uint64_t nv = place.positions.count;
  return ok && place.normals.count == nv && (place.objects.count == 0 || place.objects.count == nv) &&
         place.indices.count % 3 == 0 && std::isfinite(m.error) && m.error >= 0;
}

// After the structure: the array section, [begin, end) of the payload, each mesh's arrays one
// after the other (cluster LODs, then HLODs). Sets each array's offset (in the file: payload
// offset + head); false when the counts do not fill the section exactly.
bool place_arrays(std::vector<MappedMesh>& places, const std::vector<LodMesh>& clusters,
                  const std::vector<LodMesh>& hlods, uint64_t begin, uint64_t end, size_t head) {
  uint64_t at = begin;
  bool fits = true;
  for (size_t k = 0; k < places.size(); ++k)
    mesh_arrays(k < clusters.size() ? clusters[k] : hlods[k - clusters.size()], places[k],
                [&](const auto&, MappedArray& p) {
                  fits = fits && p.bytes <= end - at;
                  p.offset = head + at;
                  at += fits ? p.bytes : 0;
                });
  return fits && at == end;
}

// A mesh's arrays read from the mapped payload (its places from place_arrays), then checked.
bool read_mesh_arrays(const uint8_t* file, LodMesh& m, const MappedMesh& place, size_t object_count) {
  mesh_arrays(m, place, [&](auto& a, const MappedArray& p) {
    a.resize(p.count);
    if (p.bytes) std::memcpy(a.data(), file + p.offset, p.bytes);
  });
  for (uint32_t i : m.indices)
    if (i >= m.positions.size()) return false;
  for (uint32_t o : m.objects)
    if (o >= object_count) return false;
  return true;
}

// A lazily loaded mesh: released with its counts (its indices are checked when the upload reads them).
void release_lazy_mesh(LodMesh& m, const MappedMesh& place) {
  m.released = true;
  m.released_triangles = place.indices.count / 3;
  m.released_vertices = place.positions.count;
}

// The payload to `put` (see Writer).
template <class Put>
void serialize(Put& put, const std::vector<LodMesh>& clusters, const std::vector<uint32_t>& slots,
               const std::vector<LodMesh>& hlods, const std::vector<uint32_t>& hlod_of_node,
               const std::vector<std::array<double, kLeafLodLevels + 1>>& errors) {
  Writer<Put> w(put);
  w.pod(uint64_t(clusters.size()));
  for (const auto& m : clusters) write_mesh_record(w, m);
  w.vec(slots);
  w.pod(uint64_t(hlods.size()));
  for (const auto& m : hlods) write_mesh_record(w, m);
  w.vec(hlod_of_node);
  w.vec(errors);
  MappedMesh unused;  // the array section
  for (const auto* meshes : {&clusters, &hlods})
    for (const auto& m : *meshes) mesh_arrays(m, unused, [&](const auto& a, const MappedArray&) { w.raw(a); });
}

}  // namespace

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

void LodData::finish_hash() {
  uint64_t total = 0;
  auto count = [&](const void*, size_t n) { total += n; };
  serialize(count, cluster_lods_, item_slot_, hlods_, hlod_of_node_, errors_);
  StreamBytesHash hash(total);
  serialize(hash, cluster_lods_, item_slot_, hlods_, hlod_of_node_, errors_);
  hash_ = hash.value();
}

std::optional<std::string> LodData::save(const std::string& path) const {
  if (geometry_released()) return "its meshes were released after upload";
  // Three passes over the data, none holding the payload: its size, its hash, then the file
  // (header first, so a reader of a file still being written finds the header at once).
  uint64_t total = 0;
  auto count = [&](const void*, size_t n) { total += n; };
  serialize(count, cluster_lods_, item_slot_, hlods_, hlod_of_node_, errors_);
  StreamBytesHash hash(total);
  serialize(hash, cluster_lods_, item_slot_, hlods_, hlod_of_node_, errors_);
  std::error_code ec;
  std::filesystem::path p(path);
  if (p.has_parent_path()) std::filesystem::create_directories(p.parent_path(), ec);
  const std::string tmp = cache_temp_path(path);
  std::FILE* f = std::fopen(tmp.c_str(), "wb");
  if (!f) return "cannot write " + tmp;
  bool ok = true;
  auto put = [&](const void* data, size_t n) { ok = ok && std::fwrite(data, 1, n, f) == n; };
  const uint64_t value = hash.value();
  put(kCacheMagic, 8);
  put(&kCacheVersion, 4);
  put(&key_, 8);
  put(&total, 8);
  put(&value, 8);
  serialize(put, cluster_lods_, item_slot_, hlods_, hlod_of_node_, errors_);
  ok = (std::fclose(f) == 0) && ok;
  if (!ok) {
    std::filesystem::remove(tmp, ec);
    return "cannot write " + tmp + " (disk full?)";
  }
  return commit_cache_file(tmp, path);
}

std::optional<LodData> LodData::load(const std::string& path, uint64_t expected_key, const Scene& scene,
                                     const Hierarchy& h, std::string* why, bool lazy) {
  auto fail = [&](const std::string& w) -> std::optional<LodData> {
    if (why) *why = w;
    return std::nullopt;
  };
  std::string ignored;
  // Parsed straight from a read-only mapping; the pages already hashed or parsed are dropped as
  // it goes (mapped_file.hpp), so loading costs about the LOD data, not the data plus the file.
  MappedFile file;
  if (!file.open(path, why ? why : &ignored)) return std::nullopt;
  CacheHeader head;
  if (auto bad = check_cache_header(file, kCacheMagic, "LOD cache", kCacheVersion, expected_key,
                                    "stale (built for another scene, hierarchy or LOD parameters)", &head))
    return fail(*bad);
  constexpr size_t kHead = CacheHeader::kSize;
  const uint8_t* const bytes = file.data();
  const size_t file_size = file.size();
  const uint64_t key = head.key, hash = head.hash;
  const uint8_t* const payload = bytes + kHead;
  const size_t payload_size = file_size - kHead;
  // = payload_hash(payload, payload_size) (Hasher::bytes), in steps that drop what they read;
  // lazy: not the whole file at start (its structure is checked, each mesh's indices when read).
  if (!lazy) {
    Hasher hs;
    hs.u64(payload_size);
    size_t off = 0;
    for (; payload_size - off >= 8; off += 8) {
      uint64_t w;
      std::memcpy(&w, payload + off, 8);
      hs.u64(w);
      if ((off & ((size_t(32) << 20) - 1)) == 0) file.drop_before(kHead + off, 0);
    }
    uint64_t tail = 0;
    if (payload_size > off) std::memcpy(&tail, payload + off, payload_size - off);
    hs.u64(tail);
    if (hs.value() != hash) return fail("checksum mismatch (corrupt)");
    file.drop_before(file.size(), 0);
    file.restart_drops();  // the parse below reads the pages again: it drops them again
  }
  LodData d;
  d.key_ = key;
  Reader r(payload, payload_size);
  uint64_t nc = 0, nh = 0;
  std::vector<MappedMesh> places;  // cluster LODs, then HLODs
  if (!r.pod(nc) || nc > payload_size / 64) return fail("corrupt cluster LOD count");
  d.cluster_lods_.resize(nc);
  places.resize(nc);
  for (size_t k = 0; k < nc; ++k)
    if (!read_mesh_record(r, d.cluster_lods_[k], places[k])) return fail("corrupt cluster LOD mesh");
  if (!r.vec(d.item_slot_) || d.item_slot_.size() != h.items().size()) return fail("corrupt item table");
  for (size_t i = 0; i < d.item_slot_.size(); ++i)  // (slot + 1) in 64 bits: a slot of 2^32 - 1 does not wrap
    if ((uint64_t(d.item_slot_[i]) + 1) * kLeafLodLevels > nc)
      return fail("item " + std::to_string(i) + ": slot " + std::to_string(d.item_slot_[i]) + " out of range (" +
                  std::to_string(nc) + " cluster LODs)");
  if (!r.pod(nh) || nh > payload_size / 64) return fail("corrupt HLOD count");
  d.hlods_.resize(nh);
  places.resize(nc + nh);
  for (size_t k = 0; k < nh; ++k)
    if (!read_mesh_record(r, d.hlods_[k], places[nc + k])) return fail("corrupt HLOD mesh");
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
  if (!place_arrays(places, d.cluster_lods_, d.hlods_, r.offset(), payload_size, kHead))
    return fail("array section does not match the meshes' counts (truncated or trailing bytes)");
  for (size_t k = 0; k < nc + nh; ++k) {  // lazy: the arrays stay in the file; else read, in file order
    LodMesh& m = k < nc ? d.cluster_lods_[k] : d.hlods_[k - nc];
    if (lazy) {
      release_lazy_mesh(m, places[k]);
    } else {
      if (!read_mesh_arrays(bytes, m, places[k], scene.objects.size()))
        return fail(k < nc ? "corrupt cluster LOD mesh" : "corrupt HLOD mesh");
      file.drop_before(places[k].indices.offset + places[k].indices.bytes);
    }
  }
  file.drop_before(file.size(), 0);
  d.hash_ = hash;
  if (lazy && !(d.mapped_ = MappedGeometry::open(path, std::move(places), why ? why : &ignored))) return std::nullopt;
  return d;
}

// ---- Temporaries of cache files (lod_cache.hpp): named by their writer, removed when it is gone.

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
  const std::string dir = std::filesystem::path(path).parent_path().string();
  if (const size_t n = remove_stale_cache_temps(dir))
    std::cerr << who << ": removed " << n << " temporary cache file(s) of writers that are gone in " << dir << "\n";
  const uint64_t key = LodData::cache_key(h, params);
  const double t0 = now_ms();
  std::string why;
  std::optional<LodData> cached = LodData::load(path, key, scene, h, &why);
  std::optional<CacheBuildLock> building;  // held until the built data is written
  if (!cached) {  // another process may be building it: wait for that, then read again
    building.emplace(path, who);
    cached = LodData::load(path, key, scene, h, &why);
  }
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

}  // namespace occ
