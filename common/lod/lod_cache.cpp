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
constexpr uint32_t kCacheVersion = 2;
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
  // An array left in the file: its place (payload offset), after the same count check as vec.
  bool ref(MappedArray& a, size_t elem_bytes) {
    uint64_t count = 0;
    if (!pod(count) || count > (n_ - off_) / elem_bytes) return false;
    a = {uint64_t(off_), count, count * elem_bytes};
    off_ += count * elem_bytes;
    return true;
  }
  bool done() const { return off_ == n_; }
  size_t offset() const { return off_; }

 private:
  const uint8_t* p_;
  size_t n_, off_ = 0;
};

template <class W>
void write_mesh(W& w, const LodMesh& m) {
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

// read_mesh for a lazy load: the arrays' places (file offsets: payload offset + head), the mesh
// released with its counts; the indices are checked when the upload reads them.
bool read_lazy_mesh(Reader& r, LodMesh& m, MappedMesh& mm, size_t head) {
  if (!r.pod(m.origin.x) || !r.pod(m.origin.y) || !r.pod(m.origin.z) || !r.pod(m.error)) return false;
  if (!r.ref(mm.positions, 12) || !r.ref(mm.normals, 12) || !r.ref(mm.objects, 4) || !r.ref(mm.indices, 4)) return false;
  for (MappedArray* a : {&mm.positions, &mm.normals, &mm.objects, &mm.indices}) a->offset += head;
  const uint64_t nv = mm.positions.count;
  if (mm.normals.count != nv || (mm.objects.count && mm.objects.count != nv)) return false;
  if (mm.indices.count % 3 != 0 || !std::isfinite(m.error) || m.error < 0) return false;
  m.released = true;
  m.released_triangles = mm.indices.count / 3;
  m.released_vertices = nv;
  return true;
}

// The payload to `put` (see Writer).
template <class Put>
void serialize(Put& put, const std::vector<LodMesh>& clusters, const std::vector<uint32_t>& slots,
               const std::vector<LodMesh>& hlods, const std::vector<uint32_t>& hlod_of_node,
               const std::vector<std::array<double, kLeafLodLevels + 1>>& errors) {
  Writer<Put> w(put);
  w.pod(uint64_t(clusters.size()));
  for (const auto& m : clusters) write_mesh(w, m);
  w.vec(slots);
  w.pod(uint64_t(hlods.size()));
  for (const auto& m : hlods) write_mesh(w, m);
  w.vec(hlod_of_node);
  w.vec(errors);
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
  if (!r.pod(nc) || nc > payload_size) return fail("corrupt cluster LOD count");
  d.cluster_lods_.resize(nc);
  auto mapped = lazy ? std::make_shared<MappedGeometry>() : nullptr;
  auto read_one = [&](LodMesh& m) {
    if (!lazy) return read_mesh(r, m, scene.objects.size());
    mapped->meshes.emplace_back();
    return read_lazy_mesh(r, m, mapped->meshes.back(), kHead);
  };
  for (auto& m : d.cluster_lods_) {
    if (!read_one(m)) return fail("corrupt cluster LOD mesh");
    file.drop_before(kHead + r.offset());
  }
  if (!r.vec(d.item_slot_) || d.item_slot_.size() != h.items().size()) return fail("corrupt item table");
  for (size_t i = 0; i < d.item_slot_.size(); ++i)  // (slot + 1) in 64 bits: a slot of 2^32 - 1 does not wrap
    if ((uint64_t(d.item_slot_[i]) + 1) * kLeafLodLevels > nc)
      return fail("item " + std::to_string(i) + ": slot " + std::to_string(d.item_slot_[i]) + " out of range (" +
                  std::to_string(nc) + " cluster LODs)");
  if (!r.pod(nh) || nh > payload_size) return fail("corrupt HLOD count");
  d.hlods_.resize(nh);
  for (auto& m : d.hlods_) {
    if (!read_one(m)) return fail("corrupt HLOD mesh");
    file.drop_before(kHead + r.offset());
  }
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
  file.drop_before(file.size(), 0);
  d.hash_ = hash;
  if (lazy) {
    try {
      mapped->file = std::make_shared<FileReader>(path);
    } catch (const std::runtime_error& e) {
      return fail(e.what());
    }
    d.mapped_ = std::move(mapped);
  }
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
