// The scene cache (scene_cache.hpp): format, save and load.
#include "common/scene_cache.hpp"

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <type_traits>

#include "common/lod_cache.hpp"
#include "common/mapped_file.hpp"
#include "common/plant.hpp"

namespace occ {

namespace {

constexpr uint32_t kSceneCacheVersion = 3;  // 2: welded vertices, vertex cache order; 3: fetch order
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
  bool count(uint64_t& n, size_t min_bytes_each) {  // a count of records of >= min_bytes_each
    return pod(n) && n <= (f_.size() - off_) / std::max<size_t>(min_bytes_each, 1);
  }
  bool done() const { return off_ == f_.size(); }

 private:
  MappedFile& f_;
  size_t off_;
};

void write_payload(Out& o, const Scene& s, const BuildParams& p, uint32_t depth, uint64_t fp,
                   const std::vector<HNode>& nodes, const std::vector<Item>& items) {
  o.str(s.source);
  o.pod(uint64_t(s.meshes.size()));
  for (const Mesh& m : s.meshes) {
    o.str(m.name);
    o.vec(m.positions);
    o.vec(m.normals);
    o.vec(m.indices);
    o.vec(m.clusters);
    o.vec(m.uvs);
    o.vec(m.colors);
    o.pod(m.material);
  }
  o.pod(uint64_t(s.objects.size()));
  for (const Object& ob : s.objects) {
    o.pod(ob.mesh);
    o.pod(ob.transform);
    o.str(ob.name);
  }
  o.pod(uint64_t(s.materials.size()));
  for (const Material& m : s.materials) {
    o.str(m.name);
    o.pod(m.base_color);
    o.pod(m.base_color_texture);
    o.pod(m.alpha_mode);
    o.pod(m.alpha_cutoff);
    o.pod(uint8_t(m.double_sided));
    o.pod(uint8_t(m.unlit));
    o.pod(uint8_t(m.object_color));
  }
  o.vec(s.textures);
  o.pod(uint64_t(s.images.size()));
  for (const Image& im : s.images) {
    o.pod(int32_t(im.width));
    o.pod(int32_t(im.height));
    o.vec(im.rgba);
  }
  o.pod(p);
  o.pod(depth);
  o.pod(fp);
  o.vec(nodes);
  o.vec(items);
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

  static std::optional<CachedScene> load(const std::string& path, uint64_t key, std::string* why) {
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
    {
      StreamHash sh;
      constexpr size_t kStep = size_t(32) << 20;
      for (size_t off = kHead; off < f.size(); off += kStep) {
        sh.feed(f.data() + off, std::min(kStep, f.size() - off));
        f.drop_before(off + std::min(kStep, f.size() - off), 0);
      }
      if (sh.value() != head.hash) return fail("checksum mismatch (corrupt)");
      f.close();  // parse from a fresh mapping (the dropped pages come back from the page cache)
      if (!f.open(path, why)) return std::nullopt;
    }
    CachedScene c;
    Scene& s = c.scene;
    Hierarchy& h = c.hierarchy;
    In in(f, kHead);
    uint64_t n = 0;
    if (!in.str(s.source)) return fail("corrupt source name");
    if (!in.count(n, 8 * 7 + 4)) return fail("corrupt mesh count");
    s.meshes.resize(n);
    for (size_t m = 0; m < n; ++m) {
      Mesh& me = s.meshes[m];
      if (!in.str(me.name) || !in.vec(me.positions) || !in.vec(me.normals) || !in.vec(me.indices) ||
          !in.vec(me.clusters) || !in.vec(me.uvs) || !in.vec(me.colors) || !in.pod(me.material))
        return fail("mesh " + std::to_string(m) + ": truncated");
      const size_t nv = me.positions.size();
      if (me.normals.size() != nv || (!me.uvs.empty() && me.uvs.size() != nv) ||
          (!me.colors.empty() && me.colors.size() != nv) || me.indices.size() % 3 != 0)
        return fail("mesh " + std::to_string(m) + ": inconsistent array sizes");
      for (uint32_t i : me.indices)
        if (i >= nv) return fail("mesh " + std::to_string(m) + ": index out of range");
      for (const MeshCluster& cl : me.clusters)
        if (cl.index_count % 3 != 0 || uint64_t(cl.first_index) + cl.index_count > me.indices.size())
          return fail("mesh " + std::to_string(m) + ": cluster out of range");
    }
    if (!in.count(n, 4 + 128 + 8)) return fail("corrupt object count");
    s.objects.resize(n);
    for (size_t o = 0; o < n; ++o) {
      Object& ob = s.objects[o];
      if (!in.pod(ob.mesh) || !in.pod(ob.transform) || !in.str(ob.name)) return fail("object " + std::to_string(o) + ": truncated");
      if (ob.mesh >= s.meshes.size()) return fail("object " + std::to_string(o) + ": mesh out of range");
    }
    if (!in.count(n, 8)) return fail("corrupt material count");
    s.materials.resize(n);
    for (size_t k = 0; k < n; ++k) {
      Material& m = s.materials[k];
      uint8_t ds = 0, ul = 0, oc = 0;
      if (!in.str(m.name) || !in.pod(m.base_color) || !in.pod(m.base_color_texture) || !in.pod(m.alpha_mode) ||
          !in.pod(m.alpha_cutoff) || !in.pod(ds) || !in.pod(ul) || !in.pod(oc))
        return fail("material " + std::to_string(k) + ": truncated");
      if (uint8_t(m.alpha_mode) > uint8_t(AlphaMode::Blend)) return fail("material " + std::to_string(k) + ": bad alpha mode");
      m.double_sided = ds, m.unlit = ul, m.object_color = oc;
    }
    if (!in.vec(s.textures)) return fail("corrupt texture table");
    if (!in.count(n, 16)) return fail("corrupt image count");
    s.images.resize(n);
    for (size_t k = 0; k < n; ++k) {
      int32_t w = 0, hh = 0;
      if (!in.pod(w) || !in.pod(hh) || !in.vec(s.images[k].rgba)) return fail("image " + std::to_string(k) + ": truncated");
      s.images[k].width = w, s.images[k].height = hh;
      if (w < 0 || hh < 0 || s.images[k].rgba.size() != size_t(w) * size_t(hh) * 4)
        return fail("image " + std::to_string(k) + ": size mismatch");
    }
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
    if (!in.done()) return fail("trailing bytes");
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
    return c;
  }
};

bool scene_cache_applies(const std::string& spec) { return spec.rfind("plant:", 0) == 0; }

std::string scene_cache_path(const std::string& cache_dir, const std::string& spec) {
  std::string p = lod_cache_path(cache_dir, spec);  // ".../<name>-<hash>.lod"
  return p.substr(0, p.size() - 4) + ".scene";
}

uint64_t scene_cache_key(const std::string& spec, const BuildParams& params) {
  Hasher k;
  k.u32(kSceneCacheVersion);
  k.u32(plant::kGeneratorVersion);
  k.str(spec);
  k.u32(params.arity);
  k.u32(params.leaf_items);
  k.u32(params.cluster_triangles);
  return k.value();
}

std::optional<std::string> save_scene_cache(const std::string& path, uint64_t key, const Scene& scene,
                                            const Hierarchy& h) {
  return SceneCacheIo::save(path, key, scene, h);
}

std::optional<CachedScene> load_scene_cache(const std::string& path, uint64_t key, std::string* why) {
  remove_stale_cache_temps(std::filesystem::path(path).parent_path().string());
  return SceneCacheIo::load(path, key, why);
}

}  // namespace occ
