// The scene cache (scene_cache.hpp): format, save and load.
#include "common/scene/scene_cache.hpp"

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <type_traits>

#include "common/cache_files.hpp"
#include "common/mapped_file.hpp"
#include "common/scene/gltf_reader.hpp"
#include "common/scene/model_reader.hpp"
#include "common/scene/plant.hpp"

namespace occ {

namespace {

constexpr uint32_t kSceneCacheVersion = 7;  // 2: welded vertices, vertex cache order; 3: fetch order;
                                            // 4: the structure ahead of the arrays; 5: repeated triangles;
                                            // 6: flat meshes; 7: big meshes' clusters ordered one by one
constexpr char kMagic[8] = {'O', 'C', 'C', 'S', 'C', 'N', '\r', '\n'};
constexpr size_t kHead = CacheHeader::kSize;

// Buffered file writer that hashes the payload as it goes.
class Out {
 public:
  explicit Out(std::FILE* f) : f_(f) { buf_.reserve(kBuf); }
  void raw(const void* p, size_t n) {
    hash_.feed(p, n);
    bytes_ += n;
    const auto* b = static_cast<const uint8_t*>(p);
    if (buf_.size() + n > kBuf) flush();
    if (n >= kBuf) {
      ok_ &= std::fwrite(b, 1, n, f_) == n;
      return;
    }
    buf_.insert(buf_.end(), b, b + n);
  }
  template <class T>
  void pod(const T& v) {
    static_assert(std::is_trivially_copyable_v<T>);
    raw(&v, sizeof v);
  }
  template <class T>
  void vec(const std::vector<T>& v) {
    static_assert(std::is_trivially_copyable_v<T>);
    pod(uint64_t(v.size()));
    raw(v.data(), v.size() * sizeof(T));
  }
  void str(const std::string& s) {
    pod(uint64_t(s.size()));
    raw(s.data(), s.size());
  }
  // One field as the cache stores it: strings and arrays with their size first, bools as a byte.
  template <class T>
  void field(const T& v) {
    if constexpr (std::is_same_v<T, std::string>) str(v);
    else if constexpr (std::is_same_v<T, bool>) pod(uint8_t(v));
    else if constexpr (requires { v.data(); v.size(); }) vec(v);
    else pod(v);
  }
  void flush() {
    if (!buf_.empty()) ok_ &= std::fwrite(buf_.data(), 1, buf_.size(), f_) == buf_.size();
    buf_.clear();
  }
  bool ok() const { return ok_; }
  uint64_t bytes() const { return bytes_; }
  uint64_t hash() const { return hash_.value(); }

 private:
  static constexpr size_t kBuf = size_t(4) << 20;
  std::FILE* f_;
  std::vector<uint8_t> buf_;
  StreamHash hash_;
  uint64_t bytes_ = 0;
  bool ok_ = true;
};

// Parser over the mapped payload: every count is checked against the bytes left before use.
class In {
 public:
  In(MappedFile& f, size_t begin) : f_(f), off_(begin) {}
  template <class T>
  bool pod(T& v) {
    if (f_.size() - off_ < sizeof(T)) return false;
    std::memcpy(&v, f_.data() + off_, sizeof(T));
    off_ += sizeof(T);
    return true;
  }
  template <class T>
  bool vec(std::vector<T>& v) {
    uint64_t n = 0;
    if (!pod(n) || n > (f_.size() - off_) / sizeof(T)) return false;
    v.resize(n);
    if (n) std::memcpy(v.data(), f_.data() + off_, n * sizeof(T));
    off_ += n * sizeof(T);
    f_.drop_before(off_);
    return true;
  }
  bool str(std::string& s) {
    uint64_t n = 0;
    if (!pod(n) || n > f_.size() - off_) return false;
    s.assign(reinterpret_cast<const char*>(f_.data() + off_), n);
    off_ += n;
    return true;
  }
  // One field as Out::field wrote it.
  template <class T>
  bool field(T& v) {
    if constexpr (std::is_same_v<T, std::string>) return str(v);
    else if constexpr (std::is_same_v<T, bool>) {
      uint8_t b = 0;
      if (!pod(b)) return false;
      v = b;
      return true;
    } else if constexpr (requires { v.data(); v.size(); }) return vec(v);
    else return pod(v);
  }
  bool count(uint64_t& n, size_t min_bytes_each) {  // a count of records of >= min_bytes_each
    return pod(n) && n <= (f_.size() - off_) / std::max<size_t>(min_bytes_each, 1);
  }
  size_t offset() const { return off_; }

 private:
  MappedFile& f_;
  size_t off_;
};

// The fields of each record in the order the cache stores them, one list for the writer and the
// reader: f(field) for each (Out::field / In::field say how each type is stored). A mesh's record
// also holds the counts of its arrays (mesh_arrays); the arrays follow the whole structure.
template <class M, class F>
void mesh_fields(M& m, const F& f) {
  f(m.name), f(m.clusters), f(m.material), f(m.flat);
}
// The arrays of a mesh in the order the structure counts them and the array section stores
// them, each with its place in the file (MappedMesh): f(array, place).
template <class M, class P, class F>
void mesh_arrays(M& m, P& place, const F& f) {
  f(m.positions, place.positions), f(m.normals, place.normals), f(m.indices, place.indices), f(m.uvs, place.uvs),
      f(m.colors, place.colors);
}
template <class O, class F>
void object_fields(O& ob, const F& f) {
  f(ob.mesh), f(ob.transform), f(ob.name);
}
template <class M, class F>
void material_fields(M& m, const F& f) {
  f(m.name), f(m.base_color), f(m.base_color_texture), f(m.alpha_mode), f(m.alpha_cutoff), f(m.double_sided),
      f(m.unlit), f(m.object_color);
}
template <class S, class F>
void source_file_fields(S& sf, const F& f) {
  f(sf.path), f(sf.size), f(sf.mtime_ns);
}
static_assert(sizeof(Image::width) == 4 && sizeof(Image::height) == 4);  // stored as int32
template <class I, class F>
void image_fields(I& im, const F& f) {
  f(im.width), f(im.height), f(im.rgba);
}

// Writes each record of v with write_fields, after their count.
template <class T, class Fields>
void write_records(Out& o, const std::vector<T>& v, const Fields& write_fields) {
  o.pod(uint64_t(v.size()));
  for (const T& r : v) write_fields(r, [&](const auto& field) { o.field(field); });
}

// Reads a count (nullopt and "corrupt <what> count" unless the file can hold that many records
// of min_bytes each) and the records, each with read_fields ("<what> k: truncated") then checked
// by check, which returns nullptr or what is wrong ("<what> k: <what is wrong>").
template <class T, class Fields, class Check>
std::optional<std::string> read_records(In& in, std::vector<T>& v, size_t min_bytes, const std::string& what,
                                        const Fields& read_fields, const Check& check) {
  uint64_t n = 0;
  if (!in.count(n, min_bytes)) return "corrupt " + what + " count";
  v.resize(n);
  for (size_t k = 0; k < n; ++k) {
    bool ok = true;  // every field so far read
    read_fields(v[k], [&](auto& field) { ok = ok && in.field(field); });
    if (!ok) return what + " " + std::to_string(k) + ": truncated";
    if (const char* bad = check(v[k])) return what + " " + std::to_string(k) + ": " + bad;
  }
  return std::nullopt;
}

// What is wrong with a mesh read from the cache: nullptr if nothing.
const char* check_mesh(const Mesh& me) {
  const size_t nv = me.positions.size();
  if (me.normals.size() != nv || (!me.uvs.empty() && me.uvs.size() != nv) ||
      (!me.colors.empty() && me.colors.size() != nv) || me.indices.size() % 3 != 0)
    return "inconsistent array sizes";
  for (uint32_t i : me.indices)
    if (i >= nv) return "index out of range";
  for (const MeshCluster& cl : me.clusters)
    if (cl.index_count % 3 != 0 || uint64_t(cl.first_index) + cl.index_count > me.indices.size())
      return "cluster out of range";
  return nullptr;
}

// A mesh's record in the structure: its fields, and its arrays' counts into `place` (their
// offsets come with the array section, place_arrays).
bool read_mesh_record(In& in, Mesh& m, MappedMesh& place) {
  bool ok = true;
  mesh_fields(m, [&](auto& field) { ok = ok && in.field(field); });
  mesh_arrays(m, place, [&](const auto& a, MappedArray& p) {
    constexpr size_t kElem = sizeof(a[0]);
    ok = ok && in.count(p.count, kElem);
    p.bytes = p.count * kElem;
  });
  return ok;
}

// The array section, [begin, end) of the file: the meshes' arrays one after the other, in mesh
// order. Sets each array's offset; nullopt, or what is wrong when the counts do not fill the
// section exactly.
std::optional<std::string> place_arrays(std::vector<MappedMesh>& places, const std::vector<Mesh>& meshes,
                                        uint64_t begin, uint64_t end) {
  uint64_t at = begin;
  for (size_t k = 0; k < places.size(); ++k) {
    bool fits = true;
    mesh_arrays(meshes[k], places[k], [&](const auto&, MappedArray& p) {
      fits = fits && p.bytes <= end - at;
      p.offset = at;
      at += fits ? p.bytes : 0;
    });
    if (!fits) return "mesh " + std::to_string(k) + ": arrays past the end of the file";
  }
  if (at != end) return "trailing bytes";
  return std::nullopt;
}

// check_mesh for a lazy mesh, without reading its arrays (the upload checks the indices when it
// reads them); then marks it released with its counts and box (the union of its clusters').
const char* check_lazy_mesh(Mesh& me, const MappedMesh& mm) {
  const uint64_t nv = mm.positions.count;
  if (mm.normals.count != nv || (mm.uvs.count && mm.uvs.count != nv) || (mm.colors.count && mm.colors.count != nv) ||
      mm.indices.count % 3 != 0)
    return "inconsistent array sizes";
  for (const MeshCluster& cl : me.clusters)
    if (cl.index_count % 3 != 0 || uint64_t(cl.first_index) + cl.index_count > mm.indices.count)
      return "cluster out of range";
  me.released = true;
  me.released_triangles = mm.indices.count / 3;
  me.released_vertices = nv;
  for (const MeshCluster& cl : me.clusters) me.released_box.grow(cl.box);
  return nullptr;
}

void write_payload(Out& o, const Scene& s, const BuildParams& p, uint32_t depth, uint64_t fp,
                   const std::vector<HNode>& nodes, const std::vector<Item>& items) {
  o.str(s.source);
  write_records(o, s.files, [](const SourceFile& sf, const auto& f) { source_file_fields(sf, f); });
  o.pod(s.zero_area_triangles);
  o.pod(s.repeated_triangles);
  o.pod(uint64_t(s.meshes.size()));
  MappedMesh unused;
  for (const Mesh& m : s.meshes) {
    mesh_fields(m, [&](const auto& field) { o.field(field); });
    mesh_arrays(m, unused, [&](const auto& a, const MappedArray&) { o.pod(uint64_t(a.size())); });
  }
  write_records(o, s.objects, [](const Object& ob, const auto& f) { object_fields(ob, f); });
  write_records(o, s.materials, [](const Material& m, const auto& f) { material_fields(m, f); });
  o.vec(s.textures);
  write_records(o, s.images, [](const Image& im, const auto& f) { image_fields(im, f); });
  o.pod(p);
  o.pod(depth);
  o.pod(fp);
  o.vec(nodes);
  o.vec(items);
  for (const Mesh& m : s.meshes)  // the array section
    mesh_arrays(m, unused, [&](const auto& a, const MappedArray&) { o.raw(a.data(), a.size() * sizeof(a[0])); });
}

}  // namespace

// Reads and writes the private parts of a Hierarchy (a friend of it).
struct SceneCacheIo {
  static std::optional<std::string> save(const std::string& path, uint64_t key, const Scene& scene,
                                         const Hierarchy& h) {
    if (scene.geometry_released()) return "the scene's geometry was released";
    std::error_code ec;
    std::filesystem::path fp(path);
    if (fp.has_parent_path()) std::filesystem::create_directories(fp.parent_path(), ec);
    const std::string tmp = cache_temp_path(path);
    std::FILE* f = std::fopen(tmp.c_str(), "wb");
    if (!f) return "cannot write " + tmp;
    uint8_t head[kHead] = {};
    bool ok = std::fwrite(head, 1, kHead, f) == kHead;  // placeholder, rewritten below
    Out o(f);
    write_payload(o, scene, h.params_, h.depth_, h.fingerprint_, h.nodes_, h.items_);
    o.flush();
    ok &= o.ok();
    size_t at = 0;
    auto put = [&](const void* p, size_t n) {
      std::memcpy(head + at, p, n);
      at += n;
    };
    const uint64_t bytes = o.bytes(), hash = o.hash();
    put(kMagic, 8);
    put(&kSceneCacheVersion, 4);
    put(&key, 8);
    put(&bytes, 8);
    put(&hash, 8);
    ok &= std::fseek(f, 0, SEEK_SET) == 0 && std::fwrite(head, 1, kHead, f) == kHead;
    ok &= std::fclose(f) == 0;
    if (!ok) {
      std::filesystem::remove(tmp, ec);
      return "cannot write " + tmp + " (disk full?)";
    }
    return commit_cache_file(tmp, path);
  }

  static std::optional<CachedScene> load(const std::string& path, uint64_t key, std::string* why,
                                         uint64_t lazy_above_bytes) {
    auto fail = [&](const std::string& w) -> std::optional<CachedScene> {
      *why = w;
      return std::nullopt;
    };
    MappedFile f;
    if (!f.open(path, why)) return std::nullopt;
    CacheHeader head;
    if (auto bad = check_cache_header(f, kMagic, "scene cache", kSceneCacheVersion, key,
                                      "stale (written for another scene spec, generator or hierarchy parameters)", &head))
      return fail(*bad);
    // The payload's checksum, unless read lazily: not the whole file at start (its structure is
    // checked, each mesh's indices when read). Before the parse where that is known now.
    auto checksum_fits = [&] {
      StreamHash sh;
      constexpr size_t kStep = size_t(32) << 20;
      f.restart_drops();
      for (size_t off = kHead; off < f.size(); off += kStep) {
        sh.feed(f.data() + off, std::min(kStep, f.size() - off));
        f.drop_before(off + std::min(kStep, f.size() - off), 0);
      }
      f.restart_drops();  // the parse reads pages again: it drops them again
      return sh.value() == head.hash;
    };
    const bool never_lazy = lazy_above_bytes == UINT64_MAX;
    if (never_lazy && !checksum_fits()) return fail("checksum mismatch (corrupt)");
    CachedScene c;
    Scene& s = c.scene;
    Hierarchy& h = c.hierarchy;
    In in(f, kHead);
    if (!in.str(s.source)) return fail("corrupt source name");
    if (auto bad = read_records(in, s.files, 24, "source file",
                                [](SourceFile& sf, const auto& f) { source_file_fields(sf, f); },
                                [](const SourceFile&) { return nullptr; }))
      return fail(*bad);
    for (const SourceFile& was : s.files)
      if (source_file(was.path) != was)
        return fail("stale (" + was.path + " changed or is gone since the cache was written)");
    if (!in.pod(s.zero_area_triangles)) return fail("corrupt zero-area triangle count");
    if (!in.pod(s.repeated_triangles)) return fail("corrupt repeated triangle count");
    uint64_t n = 0;
    if (!in.count(n, 8 * 7 + 4)) return fail("corrupt mesh count");
    s.meshes.resize(n);
    std::vector<MappedMesh> places(n);
    for (size_t k = 0; k < n; ++k)
      if (!read_mesh_record(in, s.meshes[k], places[k])) return fail("mesh " + std::to_string(k) + ": truncated");
    if (auto bad = read_records(
            in, s.objects, 4 + 128 + 8, "object", [](Object& ob, const auto& f) { object_fields(ob, f); },
            [&](const Object& ob) { return ob.mesh >= s.meshes.size() ? "mesh out of range" : nullptr; }))
      return fail(*bad);
    if (auto bad = read_records(
            in, s.materials, 8, "material", [](Material& m, const auto& f) { material_fields(m, f); },
            [](const Material& m) { return uint8_t(m.alpha_mode) > uint8_t(AlphaMode::Blend) ? "bad alpha mode" : nullptr; }))
      return fail(*bad);
    if (!in.vec(s.textures)) return fail("corrupt texture table");
    if (auto bad = read_records(
            in, s.images, 16, "image", [](Image& im, const auto& f) { image_fields(im, f); },
            [](const Image& im) {
              const bool fits = im.width >= 0 && im.height >= 0 &&
                                im.rgba.size() == size_t(im.width) * size_t(im.height) * 4;
              return fits ? nullptr : "size mismatch";
            }))
      return fail(*bad);
    for (const Texture& t : s.textures)
      if (t.image >= s.images.size()) return fail("texture image out of range");
    for (size_t k = 0; k < s.materials.size(); ++k)
      if (const int32_t t = s.materials[k].base_color_texture; t != -1 && (t < 0 || size_t(t) >= s.textures.size()))
        return fail("material " + std::to_string(k) + ": texture out of range");
    for (size_t m = 0; m < s.meshes.size(); ++m)
      if (s.meshes[m].material != kNoMaterial && s.meshes[m].material >= s.materials.size())
        return fail("mesh " + std::to_string(m) + ": material out of range");
    if (!in.pod(h.params_) || !in.pod(h.depth_) || !in.pod(h.fingerprint_) || !in.vec(h.nodes_) || !in.vec(h.items_))
      return fail("hierarchy: truncated");
    if (auto bad = place_arrays(places, s.meshes, in.offset(), f.size())) return fail(*bad);
    const bool lazy = !never_lazy && f.size() - in.offset() > lazy_above_bytes;
    if (!lazy && !never_lazy && !checksum_fits()) return fail("checksum mismatch (corrupt)");
    for (size_t k = 0; k < n; ++k) {  // lazy: the arrays stay in the file; else read, in file order
      Mesh& m = s.meshes[k];
      const char* bad = nullptr;
      if (lazy) {
        bad = check_lazy_mesh(m, places[k]);
      } else {
        mesh_arrays(m, places[k], [&](auto& a, const MappedArray& p) {
          a.resize(p.count);
          if (p.bytes) std::memcpy(a.data(), f.data() + p.offset, p.bytes);
        });
        f.drop_before(places[k].colors.offset + places[k].colors.bytes);
        bad = check_mesh(m);
      }
      if (bad) return fail("mesh " + std::to_string(k) + ": " + bad);
    }
    if (lazy && !(s.mapped = MappedGeometry::open(path, std::move(places), why))) return std::nullopt;
    const uint64_t N = h.nodes_.size(), I = h.items_.size();
    for (size_t k = 0; k < I; ++k) {
      const Item& it = h.items_[k];
      if (it.object >= s.objects.size() || it.cluster >= s.meshes[s.objects[it.object].mesh].clusters.size())
        return fail("hierarchy: item " + std::to_string(k) + " out of range");
    }
    for (size_t k = 0; k < N; ++k) {
      const HNode& nd = h.nodes_[k];
      if ((nd.parent != kNoNode && nd.parent >= k) || uint64_t(nd.first_item) + nd.item_count > I ||
          (nd.child_count > 0 && (nd.first_child <= k || uint64_t(nd.first_child) + nd.child_count > N)))
        return fail("hierarchy: node " + std::to_string(k) + " out of range");
    }
    if (N == 0) return fail("hierarchy: no nodes");
    f.drop_before(f.size(), 0);
    return c;
  }
};

bool scene_cache_applies(const std::string& spec) {
  if (spec.rfind("layout:", 0) == 0) return false;
  return spec.rfind("plant:", 0) == 0 || is_gltf_path(spec) || is_model_path(spec);
}

uint64_t scene_array_bytes(const Scene& s) {
  uint64_t bytes = 0;
  MappedMesh unused;
  for (const Mesh& m : s.meshes)
    mesh_arrays(m, unused, [&](const auto& a, const MappedArray&) { bytes += a.size() * sizeof(a[0]); });
  return bytes;
}

std::string scene_cache_path(const std::string& cache_dir, const std::string& spec) {
  std::string p = lod_cache_path(cache_dir, spec);  // ".../<name>-<hash>.lod"
  return p.substr(0, p.size() - 4) + ".scene";
}

uint64_t scene_cache_key(const std::string& spec, const BuildParams& params, UpAxis up) {
  Hasher k;
  k.u32(kSceneCacheVersion);
  k.u32(plant::kGeneratorVersion);
  k.u32(kGltfReaderVersion);
  if (up != UpAxis::Y) k.u32(0x5a5550u);  // "ZUP": Y-up keys stay those of the builds before --up
  const bool model = !is_gltf_path(spec) && is_model_path(spec);
  if (model) k.u32(kModelReaderVersion);
  k.str(spec);
  if (is_gltf_path(spec) || model) {  // the same relative path from another folder is another file
    std::error_code ec;
    k.str(std::filesystem::weakly_canonical(spec, ec).string());
  }
  k.u32(params.arity);
  k.u32(params.leaf_items);
  k.u32(params.cluster_triangles);
  return k.value();
}

std::optional<std::string> save_scene_cache(const std::string& path, uint64_t key, const Scene& scene,
                                            const Hierarchy& h) {
  return SceneCacheIo::save(path, key, scene, h);
}

std::optional<CachedScene> load_scene_cache(const std::string& path, uint64_t key, std::string* why,
                                            uint64_t lazy_above_bytes) {
  remove_stale_cache_temps(std::filesystem::path(path).parent_path().string());
  return SceneCacheIo::load(path, key, why, lazy_above_bytes);
}

}  // namespace occ
