// The parser fuzz harnesses (contract in fuzz_targets.hpp).
#include "common/fuzz/fuzz_targets.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>

#include "common/camera_path.hpp"
#include "common/error.hpp"
#include "common/hash.hpp"
#include "common/lod/lod_cache.hpp"
#include "common/lod/lod_select.hpp"
#include "common/mapped_file.hpp"
#include "common/scene/obj_reader.hpp"
#include "common/scene/ply_reader.hpp"
#include "common/scene/scene_cache.hpp"
#include "common/scene/scene_io.hpp"
#include "common/web_input.hpp"

namespace occ::fuzz {

namespace {

// A violated property: say which and abort (a crash for libFuzzer and for the test).
[[noreturn]] void fail(const char* what, const std::string& detail = "") {
  std::fprintf(stderr, "fuzz property violated: %s%s%s\n", what, detail.empty() ? "" : ": ", detail.c_str());
  std::abort();
}

// This process's scratch folder for inputs (tmpfs where there is one), removed at exit (never
// freed: the exit handler runs after the destructors of statics made before it).
const std::string& scratch_dir() {
  static const std::string* const dir = new std::string([] {
    namespace fs = std::filesystem;
    std::error_code ec;
    const fs::path base = fs::is_directory("/dev/shm", ec) ? fs::path("/dev/shm") : fs::temp_directory_path();
    const fs::path d = base / ("occ_fuzz." + std::to_string(::getpid()));
    fs::create_directories(d, ec);
    if (ec) fail("cannot create the scratch folder", d.string());
    std::atexit([] {
      std::error_code ignored;
      std::filesystem::remove_all(scratch_dir(), ignored);
    });
    return d.string();
  }());
  return *dir;
}

std::string write_input(const char* name, std::span<const uint8_t> bytes) {
  const std::string path = scratch_dir() + "/" + name;
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0600);
  if (fd < 0) fail("cannot write the input file", path);
  for (size_t off = 0; off < bytes.size();) {
    const ssize_t n = ::write(fd, bytes.data() + off, bytes.size() - off);
    if (n <= 0) fail("cannot write the input file", path);
    off += size_t(n);
  }
  ::close(fd);
  return path;
}

// The readers' notes on std::cerr (warnings, skipped primitives) are not the subject: muted
// while a reader runs.
class MuteCerr {
 public:
  MuteCerr() : saved_(std::cerr.rdbuf(nullptr)) {}
  ~MuteCerr() {
    std::cerr.rdbuf(saved_);
    std::cerr.clear();
  }

 private:
  std::streambuf* saved_;
};

// The Scene contract (scene.hpp), checked independently of the reader that made the scene.
std::string scene_problem(const Scene& s) {
  for (size_t m = 0; m < s.meshes.size(); ++m) {
    const Mesh& me = s.meshes[m];
    const size_t nv = me.positions.size();
    const std::string at = "mesh " + std::to_string(m) + ": ";
    if (me.normals.size() != nv) return at + "normals and positions differ in size";
    if ((!me.uvs.empty() && me.uvs.size() != nv) || (!me.colors.empty() && me.colors.size() != nv))
      return at + "uvs or colours differ in size";
    if (me.indices.size() % 3) return at + "index count not a multiple of 3";
    if (std::any_of(me.indices.begin(), me.indices.end(), [&](uint32_t i) { return i >= nv; }))
      return at + "index out of range";
    for (const MeshCluster& c : me.clusters)
      if (c.index_count % 3 || uint64_t(c.first_index) + c.index_count > me.indices.size())
        return at + "cluster out of range";
    if (me.material != kNoMaterial && me.material >= s.materials.size()) return at + "material out of range";
  }
  for (const Object& o : s.objects)
    if (o.mesh >= s.meshes.size()) return "object mesh out of range";
  for (const Material& m : s.materials)
    if (m.base_color_texture != -1 && (m.base_color_texture < 0 || size_t(m.base_color_texture) >= s.textures.size()))
      return "material texture out of range";
  for (const Texture& t : s.textures)
    if (t.image >= s.images.size()) return "texture image out of range";
  for (const Image& im : s.images)
    if (im.width < 0 || im.height < 0 || im.rgba.size() != size_t(im.width) * size_t(im.height) * 4)
      return "image size mismatch";
  return "";
}

// An InputError of a file reader must name the file.
void check_names_file(const InputError& e, const std::string& path) {
  if (std::string_view(e.what()).rfind(path, 0) != 0) fail("error does not start with the file name", e.what());
}

// A scene file reader's contract on `input` written as the file `name`: InputError naming the
// file, or a scene that keeps the Scene contract before and after the hierarchy build.
Verdict scene_file(const char* name, std::span<const uint8_t> input, Scene (*read)(const std::string&),
                   const char* reader) {
  const std::string path = write_input(name, input);
  Scene s;
  try {
    MuteCerr mute;
    s = read(path);
  } catch (const InputError& e) {
    check_names_file(e, path);
    return Verdict::Rejected;
  } catch (const std::exception& e) {
    fail((std::string(reader) + " threw something other than InputError").c_str(), e.what());
  }
  if (auto p = scene_problem(s); !p.empty()) fail((std::string(reader) + " accepted a broken scene").c_str(), p);
  (void)s.bounds();
  (void)s.content_hash();
  const Hierarchy h = Hierarchy::build(s, kFixtureBuild);  // what a host does next (splits clusters)
  if (auto p = scene_problem(s); !p.empty()) fail("the hierarchy build broke the scene", p);
  if (h.size() == 0) fail("no hierarchy nodes");
  return Verdict::Accepted;
}

// No extension: glTF or GLB by its magic.
Verdict gltf(std::span<const uint8_t> input) { return scene_file("input", input, load_gltf, "load_gltf"); }
Verdict ply(std::span<const uint8_t> input) { return scene_file("input.ply", input, load_ply, "load_ply"); }
Verdict obj(std::span<const uint8_t> input) { return scene_file("input.obj", input, load_obj, "load_obj"); }

Verdict camera_path(std::span<const uint8_t> input) {
  const std::string path = write_input("input.csv", input);
  const Aabb bounds{{-10, 0, -10}, {10, 5, 10}};
  std::vector<Camera> cams;
  try {
    cams = load_camera_path(path, bounds, Viewport{64, 48});
  } catch (const InputError& e) {
    check_names_file(e, path);
    return Verdict::Rejected;
  } catch (const std::exception& e) {
    fail("load_camera_path threw something other than InputError", e.what());
  }
  if (cams.empty()) fail("an accepted camera path has no cameras");
  for (const Camera& c : cams)
    if (auto why = c.invalid_reason()) fail("an accepted camera is invalid", *why);
  return Verdict::Accepted;
}

// The two caches share a header (mapped_file.hpp): magic, version, key (12..20), payload size
// (20..28), payload hash (28..36). A copy of `in` whose size and hash fit its payload.
constexpr size_t kHead = CacheHeader::kSize;
uint64_t key_of(std::span<const uint8_t> in) {
  uint64_t key = 0;
  if (in.size() >= kHead) std::memcpy(&key, in.data() + 12, 8);
  return key;
}
std::vector<uint8_t> with_fitting_header(std::span<const uint8_t> in, uint64_t payload_hash) {
  std::vector<uint8_t> b(in.begin(), in.end());
  const uint64_t size = b.size() - kHead;
  std::memcpy(b.data() + 20, &size, 8);
  std::memcpy(b.data() + 28, &payload_hash, 8);
  return b;
}

// Loads the bytes as they are, then (when the header is there) with a fitting size and hash.
template <class Load>
Verdict load_cache(const char* name, std::span<const uint8_t> input, uint64_t (*hash)(std::span<const uint8_t>),
                   Load load) {
  const std::string path = write_input(name, input);
  const uint64_t key = key_of(input);
  std::string why;
  bool ok = load(path, key, &why);
  if (!ok && why.empty()) fail("a cache was rejected without a reason");
  if (input.size() < kHead) return ok ? Verdict::Accepted : Verdict::Rejected;
  const std::vector<uint8_t> fitted = with_fitting_header(input, hash(input.subspan(kHead)));
  if (std::equal(fitted.begin(), fitted.end(), input.begin(), input.end())) return ok ? Verdict::Accepted : Verdict::Rejected;
  write_input(name, fitted);
  why.clear();
  ok = load(path, key, &why);
  if (!ok && why.empty()) fail("a cache was rejected without a reason");
  return ok ? Verdict::Accepted : Verdict::Rejected;
}

Verdict scene_cache(std::span<const uint8_t> input) {
  auto hash = [](std::span<const uint8_t> p) {
    StreamHash h;
    h.feed(p.data(), p.size());
    return h.value();
  };
  return load_cache("input.scene", input, hash, [](const std::string& path, uint64_t key, std::string* why) {
    std::optional<CachedScene> c = load_scene_cache(path, key, why);
    if (!c) return false;
    if (auto p = scene_problem(c->scene); !p.empty()) fail("the scene cache accepted a broken scene", p);
    const Hierarchy& h = c->hierarchy;
    if (h.size() == 0) fail("the scene cache accepted an empty hierarchy");
    for (const Item& it : h.items())
      if (it.object >= c->scene.objects.size() ||
          it.cluster >= c->scene.meshes[c->scene.objects[it.object].mesh].clusters.size())
        fail("the scene cache accepted an item out of range");
    for (uint32_t id = 0; id < h.size(); ++id) {
      const HNode& n = h.node(id);
      if (uint64_t(n.first_item) + n.item_count > h.items().size() ||
          (n.child_count && uint64_t(n.first_child) + n.child_count > h.size()))
        fail("the scene cache accepted a node out of range", std::to_string(id));
    }
    return true;
  });
}

Verdict lod_cache(std::span<const uint8_t> input) {
  auto hash = [](std::span<const uint8_t> p) {
    Hasher h;
    h.bytes(p.data(), p.size());
    return h.value();
  };
  return load_cache("input.lod", input, hash, [](const std::string& path, uint64_t key, std::string* why) {
    const Fixture& f = fixture();
    std::optional<LodData> d = LodData::load(path, key, f.scene, f.hierarchy, why);
    if (!d) return false;
    const Hierarchy& h = f.hierarchy;
    // What the selector and the renderers read, through the accessors they use.
    for (uint32_t item = 0; item < h.items().size(); ++item) {
      if ((uint64_t(d->item_slots()[item]) + 1) * kLeafLodLevels > d->cluster_lods().size())
        fail("the LOD cache accepted an item slot out of range", std::to_string(item));
      for (uint32_t l = 1; l <= kLeafLodLevels; ++l) (void)d->item_lod(item, l).triangles();
    }
    for (uint32_t id = 0; id < h.size(); ++id) {
      if (const LodMesh* m = d->hlod(id)) (void)m->triangles();
      for (uint32_t l = 0; l <= kLeafLodLevels; ++l) (void)d->error(id, l);
    }
    (void)lod_benefit(*d, h);
    return true;
  });
}

// One WebSocket input message of render_client --web, parsed in memory (no file: the page's
// bytes reach the parser as they are). What is accepted is in range and reads back the same
// from its formatted form.
Verdict web_input(std::span<const uint8_t> input) {
  const std::string_view msg(reinterpret_cast<const char*>(input.data()), input.size());
  auto parsed = parse_web_input(msg);
  if (const auto* why = std::get_if<std::string>(&parsed)) {
    if (why->empty() || why->find('\n') != std::string::npos) fail("web input rejected without a one-line reason");
    return Verdict::Rejected;
  }
  const WebInput& in = std::get<WebInput>(parsed);
  using K = WebInput::Kind;
  const bool key = in.kind == K::key_down || in.kind == K::key_up;
  const bool button = in.kind == K::button_down || in.kind == K::button_up;
  if (in.seq == 0 || in.seq > 0x7fffffffu || (key && in.key == WebKey::none) || (button && (in.button < 1 || in.button > 3)) ||
      std::abs(in.x) > 100000 || std::abs(in.y) > 100000 || std::abs(in.notches) > 100 ||
      (in.kind == K::wheel && in.notches == 0))
    fail("web input accepted out of range", std::string(msg));
  const auto again = parse_web_input(format_web_input(in));
  if (!std::holds_alternative<WebInput>(again) || std::get<WebInput>(again) != in)
    fail("web input does not read back from its formatted form", std::string(msg));
  return Verdict::Accepted;
}

constexpr Target kTargets[] = {{"gltf", gltf},   {"camera_path", camera_path}, {"scene_cache", scene_cache},
                               {"lod_cache", lod_cache}, {"ply", ply}, {"obj", obj}, {"web_input", web_input}};

}  // namespace

std::span<const Target> targets() { return kTargets; }

const Target* find_target(std::string_view name) {
  for (const Target& t : kTargets)
    if (name == t.name) return &t;
  return nullptr;
}

const Fixture& fixture() {
  static const Fixture f = [] {
    Fixture x;
    x.scene = load_scene("hard:walls:1");
    x.hierarchy = Hierarchy::build(x.scene, kFixtureBuild);
    return x;
  }();
  return f;
}

void mutate(std::vector<uint8_t>& b, const std::vector<uint8_t>& other, std::mt19937_64& rng) {
  static const char* const kTokens[] = {",", "\n", "\r\n", "#", " ", "\"", "{", "}", "[", "]", ":", "0", "-1", "1e308",
                                        "nan", "inf", "-0", "4294967295", "2147483648", "0.5", "\"uri\"",
                                        "\"bufferView\"", "\"count\"", "\"byteOffset\"", "\"children\"", "null"};
  static const uint64_t kNumbers[] = {0, 1, 2, 3, 0xff, 0xffff, 0x7fffffff, 0x80000000, 0xffffffff,
                                      0xffffffffffffffffULL, 0x7ff8000000000000ULL, 0x7ff0000000000000ULL};
  const auto pick = [&](size_t n) { return n ? size_t(rng() % n) : 0; };
  for (int e = 1 + int(rng() % 3); e > 0; --e) {
    switch (rng() % 8) {
      case 0:  // flip a bit
        if (!b.empty()) b[pick(b.size())] ^= uint8_t(1u << (rng() % 8));
        break;
      case 1:  // a random byte
        if (!b.empty()) b[pick(b.size())] = uint8_t(rng());
        break;
      case 2:  // truncate
        b.resize(pick(b.size() + 1));
        break;
      case 3: {  // erase a run
        const size_t at = pick(b.size() + 1), n = std::min(b.size() - at, size_t(1 + rng() % 16));
        b.erase(b.begin() + ptrdiff_t(at), b.begin() + ptrdiff_t(at + n));
        break;
      }
      case 4: {  // insert a text token
        const char* t = kTokens[pick(std::size(kTokens))];
        b.insert(b.begin() + ptrdiff_t(pick(b.size() + 1)), t, t + std::strlen(t));
        break;
      }
      case 5: {  // an interesting number over 4 or 8 bytes
        const uint64_t v = kNumbers[pick(std::size(kNumbers))];
        const size_t w = rng() % 2 ? 4 : 8;
        if (b.size() >= w) std::memcpy(b.data() + pick(b.size() - w + 1), &v, w);
        break;
      }
      case 6: {  // a chunk of another input
        if (other.empty()) break;
        const size_t from = pick(other.size()), n = std::min(other.size() - from, size_t(1 + rng() % 64));
        b.insert(b.begin() + ptrdiff_t(pick(b.size() + 1)), other.begin() + ptrdiff_t(from),
                 other.begin() + ptrdiff_t(from + n));
        break;
      }
      case 7:  // junk at the end
        for (int i = 1 + int(rng() % 8); i > 0; --i) b.push_back(uint8_t(rng()));
        break;
    }
  }
}

std::vector<std::vector<uint8_t>> read_seeds(const std::string& dir) {
  std::vector<std::filesystem::path> files;
  for (const auto& e : std::filesystem::directory_iterator(dir))
    if (e.is_regular_file()) files.push_back(e.path());
  std::sort(files.begin(), files.end());
  std::vector<std::vector<uint8_t>> seeds;
  for (const auto& p : files) {
    std::ifstream in(p, std::ios::binary);
    seeds.emplace_back(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }
  return seeds;
}

}  // namespace occ::fuzz
