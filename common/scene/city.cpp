// The procedural city (city.hpp): box buildings with window-grid facades on city blocks.
#include "common/scene/city.hpp"

#include <glm/gtc/matrix_transform.hpp>
#include <map>
#include <tuple>

#include "common/hash.hpp"
#include "common/scene/scene_shapes.hpp"

namespace occ {
namespace {

// splitmix64: identical sequence on every platform and standard library.
class Rng {
 public:
  explicit Rng(uint64_t seed) : s_(seed) {}
  int uniform(int lo, int hi) { return lo + int(mix64(s_ += 0x9e3779b97f4a7c15ULL) % uint64_t(hi - lo + 1)); }

 private:
  uint64_t s_;
};

// A w x d box building of `floors` floors with its corner at the origin (x in [0,w], z in [0,d]).
// Each facade is a window grid of (floors * detail) rows x (bays * detail) columns, with one
// window bay per facade under 15 m and two otherwise; the roof is one quad, there is no floor.
// Triangles: 4 * rows * detail * (bays(w) + bays(d)) + 2.
Mesh building_mesh(int w, int d, int floors, int detail) {
  Mesh m;
  m.name = "building " + std::to_string(w) + "x" + std::to_string(d) + "x" + std::to_string(floors);
  const auto fw = float(w), fd = float(d), h = float(floors * city::kFloorHeight);
  const glm::vec3 up(0, h, 0);
  const int rows = floors * detail;
  auto cols = [&](int len) { return (len < 15 ? 1 : 2) * detail; };
  add_grid(m, {0, 0, fd}, {fw, 0, 0}, up, rows, cols(w));    // +z
  add_grid(m, {fw, 0, 0}, {-fw, 0, 0}, up, rows, cols(w));   // -z
  add_grid(m, {fw, 0, fd}, {0, 0, -fd}, up, rows, cols(d));  // +x
  add_grid(m, {0, 0, 0}, {0, 0, fd}, up, rows, cols(d));     // -x
  add_grid(m, up, {0, 0, fd}, {fw, 0, 0}, 1, 1);             // roof, +y
  return m;
}

}  // namespace

// Lot (a, b) of block (i, j) holds building k = a * n + b with footprint w x d (10..20 m in 2 m
// steps) at a random offset inside the lot and 1..floors_max floors; meshes are shared between
// buildings of equal (w, d, floors). Each block also has a ground square (the block plus half of
// the surrounding streets, so the ground tiles the city). Sizes (checked by the scene tests):
//   city (10x10:4:12:2)   1700 objects,   500,488 triangles drawn
//   city:20x20:4:16:2     6800 objects, 2,613,280 triangles drawn (the >= 2M scene)
Scene generate_city(const CityParams& p) {
  check_range("city", "blocks", p.blocks_x, 1, city::kMaxBlocks);
  check_range("city", "blocks", p.blocks_z, 1, city::kMaxBlocks);
  check_range("city", "buildings per block", p.buildings_per_block, 1, city::kMaxBuildings);
  check_range("city", "floors", p.floors_max, 1, city::kMaxFloors);
  check_range("city", "detail", p.detail, 1, city::kMaxDetail);

  Scene scene;
  scene.source = "city";
  const auto pitch = float(city::block_pitch(p));
  Mesh ground;
  ground.name = "ground";
  add_grid(ground, {0, 0, 0}, {0, 0, pitch}, {pitch, 0, 0}, 1, 1);
  scene.meshes.push_back(std::move(ground));

  Rng rng(p.seed);
  std::map<std::tuple<int, int, int>, uint32_t> cache;  // (w, d, floors) -> mesh
  const int n = p.buildings_per_block;
  for (int i = 0; i < p.blocks_x; ++i)
    for (int j = 0; j < p.blocks_z; ++j) {
      const std::string block = "block " + std::to_string(i) + "," + std::to_string(j);
      const Aabb area = city::block_area(p, i, j);
      const glm::dvec3 corner = area.min - glm::dvec3(0.5 * city::kStreet, 0, 0.5 * city::kStreet);
      scene.objects.push_back(Object{0, glm::translate(glm::dmat4(1.0), corner), block + " ground"});
      for (int k = 0; k < n * n; ++k) {
        const int w = 2 * rng.uniform(5, 10), d = 2 * rng.uniform(5, 10),
                  floors = rng.uniform(1, p.floors_max);
        const int ox = rng.uniform(0, int(city::kLot) - w), oz = rng.uniform(0, int(city::kLot) - d);
        const glm::dvec3 lot = area.min + glm::dvec3(k / n, 0, k % n) * city::kLot;
        auto [it, fresh] = cache.try_emplace({w, d, floors}, uint32_t(scene.meshes.size()));
        if (fresh) scene.meshes.push_back(building_mesh(w, d, floors, p.detail));
        scene.objects.push_back(Object{it->second,
                                       glm::translate(glm::dmat4(1.0), lot + glm::dvec3(ox, 0, oz)),
                                       block + " building " + std::to_string(k)});
      }
    }
  return scene;
}

}  // namespace occ
