// LOD/HLOD build, error projection, selection and the binary cache (no GL).
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>

#include "common/lod/lod.hpp"
#include "common/scene/scene_io.hpp"
#include "scene_fixtures.hpp"

using namespace occ;
namespace fs = std::filesystem;

namespace {

struct Built {
  Scene scene;
  Hierarchy h;
  LodData lod;
};

Built small_city(int blocks = 3, uint32_t seed = 1) {
  Built b{generate_city(occtest::city_params(blocks, blocks, 2, 6, 2, seed)), {}, {}};
  BuildParams bp;
  bp.cluster_triangles = 256;  // several clusters per building: leaves with more triangles
  b.h = Hierarchy::build(b.scene, bp);
  b.lod = LodData::build(b.scene, b.h, {});
  return b;
}

fs::path temp_dir(const std::string& name) {
  fs::path d = fs::temp_directory_path() / ("occ_lod_" + std::to_string(::getpid()) + "_" + name);
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

Camera random_camera(std::mt19937& rng, const Aabb& b) {
  std::uniform_real_distribution<double> u(0, 1);
  const glm::dvec3 e = b.extent();
  glm::dvec3 eye = b.min + glm::dvec3(u(rng) * e.x, 1.7 + u(rng) * e.y * 1.5, u(rng) * e.z);
  glm::dvec3 target = b.min + glm::dvec3(u(rng) * e.x, u(rng) * e.y, u(rng) * e.z);
  if (glm::length(target - eye) < 1) target = eye + glm::dvec3(1, 0, 0);
  return Camera::look_at(eye, target, {0, 1, 0}, 30 + 60 * u(rng), 4.0 / 3.0, 0.1, 1e4);
}

}  // namespace

TEST(LodError, ProjectionMatchesFormula) {
  const double fovy = glm::radians(60.0);
  const double expect = 0.5 * 600 / (2 * 10 * std::tan(fovy / 2));
  EXPECT_NEAR(projected_error_px(0.5, 10, 600, fovy), expect, 1e-12);
  // Twice as far: half the pixels; twice the viewport: twice the pixels.
  EXPECT_NEAR(projected_error_px(0.5, 20, 600, fovy), expect / 2, 1e-12);
  EXPECT_NEAR(projected_error_px(0.5, 10, 1200, fovy), expect * 2, 1e-12);
}

TEST(LodError, CameraInsideOrOnTheBoxIsInfiniteWithoutDividingByZero) {
  EXPECT_TRUE(std::isinf(projected_error_px(0.1, 0.0, 600, 1.0)));
  EXPECT_TRUE(std::isinf(projected_error_px(0.1, -1.0, 600, 1.0)));
  EXPECT_TRUE(std::isinf(projected_error_px(0.0, 0.0, 600, 1.0)));  // even a zero error: inside is inside
  EXPECT_EQ(projected_error_px(0.0, 5.0, 600, 1.0), 0.0);
  // Through the selector: eye inside a leaf's box -> level 0 whatever tau.
  Built b = small_city(2);
  Renderables r(b.h, &b.lod);
  uint32_t leaf = 0;
  while (!b.h.node(leaf).leaf()) ++leaf;
  Camera cam = Camera::look_at(b.h.node(leaf).box.center(), b.h.node(leaf).box.center() + glm::dvec3(1, 0, 0),
                               {0, 1, 0}, 60, 1, 0.1, 100);
  LodSelector sel(r, cam, 600, 1e9);
  EXPECT_TRUE(std::isinf(sel.error_px(leaf, kLeafLodLevels)));
  EXPECT_EQ(sel.leaf_level(leaf), 0u);
  EXPECT_FALSE(sel.satisfies(0));  // the root contains the eye
}

TEST(LodError, HugeDistancesGiveTinyFiniteErrors) {
  const double e = projected_error_px(1.0, 1e300, 1e4, 1.0);
  EXPECT_TRUE(std::isfinite(e));
  EXPECT_GE(e, 0.0);
  EXPECT_LT(e, 1e-290);
  EXPECT_TRUE(std::isfinite(projected_error_px(1e30, 1e-300, 1e4, 1e-6)) ||
              std::isinf(projected_error_px(1e30, 1e-300, 1e4, 1e-6)));  // no NaN
  EXPECT_FALSE(std::isnan(projected_error_px(1e30, 1e-300, 1e4, 1e-6)));
}

TEST(LodBuild, ChainsShrinkAndErrorsAreMonotone) {
  Built b = small_city(3);
  const LodData& d = b.lod;
  ASSERT_EQ(d.item_slots().size(), b.h.items().size());
  uint64_t before = 0, coarse = 0;
  for (uint32_t i = 0; i < b.h.items().size(); ++i) {
    before += b.h.items()[i].triangles;
    coarse += d.item_lod(i, kLeafLodLevels).triangles();
    for (uint32_t l = 2; l <= kLeafLodLevels; ++l) {
      EXPECT_LE(d.item_lod(i, l).triangles(), d.item_lod(i, l - 1).triangles());
      EXPECT_GE(d.item_lod(i, l).error, d.item_lod(i, l - 1).error);
    }
  }
  EXPECT_LT(coarse, before / 2);  // the simplifier did reduce
  for (uint32_t id = 0; id < b.h.size(); ++id) {
    const HNode& n = b.h.node(id);
    if (n.item_count == 0) continue;
    if (n.leaf()) {
      EXPECT_EQ(d.error(id, 0), 0.0);
      for (uint32_t l = 1; l <= kLeafLodLevels; ++l) EXPECT_GE(d.error(id, l), d.error(id, l - 1));
    } else {
      ASSERT_NE(d.hlod(id), nullptr) << id;
      EXPECT_GT(d.hlod(id)->triangles(), 0u);
      for (uint32_t c = n.first_child; c < n.first_child + n.child_count; ++c)
        if (b.h.node(c).item_count > 0) {
          EXPECT_GE(d.coarsest_error(id), d.coarsest_error(c)) << id << " " << c;
        }
      // HLOD vertices stay within (a little outside of) the node's box.
      const LodMesh& m = *d.hlod(id);
      Aabb box = n.box;
      const double pad = 1e-3 * box.diagonal() + d.coarsest_error(id);
      for (const glm::vec3& p : m.positions) {
        glm::dvec3 w = m.origin + glm::dvec3(p);
        EXPECT_LE(box.distance2(w), pad * pad);
      }
    }
  }
  // The root HLOD is much smaller than the scene.
  EXPECT_LT(d.hlod(0)->triangles(), b.scene.triangle_count() / 4);
}

TEST(LodBuild, Deterministic) {
  Built a = small_city(2), b = small_city(2);
  EXPECT_EQ(a.lod.hash(), b.lod.hash());
  Built c = small_city(2, 7);
  EXPECT_NE(a.lod.hash(), c.lod.hash());
}

TEST(LodSelect, TauZeroSelectsOriginalGeometryOnly) {
  Built b = small_city(3);
  Renderables r(b.h, &b.lod);
  std::mt19937 rng(3);
  for (int k = 0; k < 20; ++k) {
    LodSelector sel(r, random_camera(rng, b.h.node(0).box), 600, 0.0);
    for (uint32_t id = 0; id < b.h.size(); ++id) {
      if (b.h.node(id).leaf()) {
        EXPECT_EQ(sel.leaf_level(id), 0u);
        EXPECT_EQ(sel.renderable(id), id);
      } else {
        EXPECT_FALSE(sel.satisfies(id));
      }
    }
  }
}

TEST(LodSelect, CoarsestLevelWithinTau) {
  Built b = small_city(3);
  Renderables r(b.h, &b.lod);
  std::mt19937 rng(5);
  for (double tau : {0.5, 1.0, 2.0, 5.0, 20.0}) {
    for (int k = 0; k < 10; ++k) {
      LodSelector sel(r, random_camera(rng, b.h.node(0).box), 600, tau);
      for (uint32_t id = 0; id < b.h.size(); ++id) {
        const HNode& n = b.h.node(id);
        if (n.item_count == 0) continue;
        if (n.leaf()) {
          const uint32_t l = sel.leaf_level(id);
          if (l > 0) {
            EXPECT_LE(sel.error_px(id, l), tau);  // level 0 (the original) always fits
          }
          if (l < kLeafLodLevels) {
            EXPECT_GT(sel.error_px(id, l + 1), tau);  // coarsest that fits
          }
          EXPECT_EQ(r.node_of(sel.renderable(id)), id);
          EXPECT_EQ(r.level_of(sel.renderable(id)), l);
        } else if (sel.satisfies(id)) {
          EXPECT_LE(sel.error_px(id, 0), tau);
          for (uint32_t c = n.first_child; c < n.first_child + n.child_count; ++c)
            EXPECT_TRUE(sel.satisfies(c));  // monotone: a satisfying parent's children satisfy
        }
      }
    }
  }
}

TEST(LodRenderables, IdsRoundTrip) {
  Built b = small_city(2);
  Renderables r(b.h, &b.lod);
  uint32_t leaves = 0;
  for (uint32_t id = 0; id < b.h.size(); ++id) leaves += b.h.node(id).leaf();
  EXPECT_EQ(r.count(), b.h.size() + leaves * kLeafLodLevels);
  std::vector<bool> seen(r.count(), false);
  for (uint32_t id = 0; id < b.h.size(); ++id) {
    if (!b.h.node(id).leaf()) {
      EXPECT_EQ(r.node_of(id), id);
      EXPECT_EQ(r.level_of(id), 0u);
      continue;
    }
    for (uint32_t l = 0; l <= kLeafLodLevels; ++l) {
      const uint32_t x = r.id(id, l);
      ASSERT_LT(x, r.count());
      EXPECT_FALSE(seen[x]);
      seen[x] = true;
      EXPECT_EQ(r.node_of(x), id);
      EXPECT_EQ(r.level_of(x), l);
    }
  }
}

TEST(LodCache, RoundTripIsIdentical) {
  Built b = small_city(2);
  fs::path dir = temp_dir("roundtrip");
  const std::string path = (dir / "c.lod").string();
  ASSERT_FALSE(b.lod.save(path).has_value());
  std::string why;
  auto back = LodData::load(path, LodData::cache_key(b.h, {}), b.scene, b.h, &why);
  ASSERT_TRUE(back.has_value()) << why;
  EXPECT_EQ(back->hash(), b.lod.hash());
  EXPECT_EQ(back->total_triangles(), b.lod.total_triangles());
  for (uint32_t id = 0; id < b.h.size(); ++id)
    for (uint32_t l = 0; l <= kLeafLodLevels; ++l) EXPECT_EQ(back->error(id, l), b.lod.error(id, l));
  // Other parameters: stale.
  LodParams other;
  other.hlod_ratio = 0.5f;
  EXPECT_FALSE(LodData::load(path, LodData::cache_key(b.h, other), b.scene, b.h, &why).has_value());
  EXPECT_NE(why.find("stale"), std::string::npos) << why;
  fs::remove_all(dir);
}

TEST(LodCache, CorruptFilesAreRejectedNeverTrusted) {
  Built b = small_city(2);
  fs::path dir = temp_dir("corrupt");
  const std::string path = (dir / "c.lod").string();
  ASSERT_FALSE(b.lod.save(path).has_value());
  std::ifstream in(path, std::ios::binary);
  std::vector<char> good((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const uint64_t key = LodData::cache_key(b.h, {});
  auto write = [&](const std::vector<char>& bytes) {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(bytes.data(), std::streamsize(bytes.size()));
  };
  std::string why;
  // Truncations at many lengths.
  for (size_t len : {size_t(0), size_t(3), size_t(8), size_t(20), size_t(35), size_t(36), good.size() / 2,
                     good.size() - 1}) {
    write(std::vector<char>(good.begin(), good.begin() + std::min(len, good.size())));
    EXPECT_FALSE(LodData::load(path, key, b.scene, b.h, &why).has_value()) << len;
    EXPECT_FALSE(why.empty());
  }
  // Bit flips anywhere (header and payload).
  std::mt19937 rng(11);
  for (int k = 0; k < 200; ++k) {
    std::vector<char> bad = good;
    const size_t at = k < 36 ? size_t(k) : rng() % bad.size();
    bad[at] = char(bad[at] ^ (1 << (rng() % 8)));
    write(bad);
    EXPECT_FALSE(LodData::load(path, key, b.scene, b.h, &why).has_value()) << at;
  }
  // Trailing garbage.
  std::vector<char> longer = good;
  longer.push_back('x');
  write(longer);
  EXPECT_FALSE(LodData::load(path, key, b.scene, b.h, &why).has_value());
  // load_or_build: a corrupt cache is rebuilt and rewritten; the next load uses it.
  write(std::vector<char>(good.begin(), good.begin() + 100));
  const std::string spec = "test-scene";
  const std::string cpath = lod_cache_path(dir.string(), spec);
  fs::copy_file(path, cpath, fs::copy_options::overwrite_existing);
  testing::internal::CaptureStderr();
  LodData rebuilt = load_or_build_lod(b.scene, b.h, {}, dir.string(), spec, "test");
  std::string err = testing::internal::GetCapturedStderr();
  EXPECT_NE(err.find("unusable"), std::string::npos) << err;
  EXPECT_NE(err.find("rebuilding"), std::string::npos) << err;
  EXPECT_EQ(rebuilt.hash(), b.lod.hash());
  testing::internal::CaptureStderr();
  LodData again = load_or_build_lod(b.scene, b.h, {}, dir.string(), spec, "test");
  err = testing::internal::GetCapturedStderr();
  EXPECT_NE(err.find("loaded"), std::string::npos) << err;
  EXPECT_EQ(again.hash(), b.lod.hash());
  fs::remove_all(dir);
}

// The simplified meshes keep the shape: each LOD's box matches its original cluster's box
// within the reported error (a vanished or shifted building would fail this).
TEST(LodBuild, LodBoxesMatchOriginalWithinError) {
  Built b = small_city(3);
  for (uint32_t i = 0; i < b.h.items().size(); ++i) {
    const Item& it = b.h.items()[i];
    const Mesh& mesh = b.scene.meshes[b.scene.objects[it.object].mesh];
    const Aabb orig = mesh.clusters[it.cluster].box;
    for (uint32_t l = 1; l <= kLeafLodLevels; ++l) {
      const LodMesh& m = b.lod.item_lod(i, l);
      Aabb box;
      for (uint32_t idx : m.indices) box.grow(glm::dvec3(m.positions[idx]));
      const double tol = m.error + 1e-4 * (1 + orig.diagonal());
      ASSERT_FALSE(box.empty()) << "item " << i << " level " << l;
      for (int a = 0; a < 3; ++a) {
        EXPECT_NEAR(box.min[a], orig.min[a], tol) << "item " << i << " level " << l << " axis " << a;
        EXPECT_NEAR(box.max[a], orig.max[a], tol) << "item " << i << " level " << l << " axis " << a;
      }
    }
  }
}

// "Only the effects a scene calls for": a scene whose geometry the simplifier cannot reduce gets
// benefit ~0 (load_and_build then drops its LODs); a city gets a large one.
TEST(LodBenefit, LowPolyScenesHaveNoneCitiesHaveMuch) {
  Scene s;
  Mesh tri;
  tri.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  tri.indices = {0, 1, 2};
  compute_normals(tri);
  s.meshes.push_back(tri);
  for (int i = 0; i < 4; ++i)
    s.objects.push_back({0, glm::translate(glm::dmat4(1.0), glm::dvec3(3.0 * i, 0, 0)), ""});
  const Hierarchy h = Hierarchy::build(s, BuildParams{});
  const LodData lod = LodData::build(s, h, {});
  const LodBenefit low = lod_benefit(lod, h);
  EXPECT_GE(low.fraction, 0.0);
  EXPECT_LT(low.fraction, LodBenefit::kMinFraction);
  EXPECT_FALSE(low.worth_selecting());

  Built city = small_city();
  const LodBenefit high = lod_benefit(city.lod, city.h);
  EXPECT_GT(high.fraction, 0.5);
  EXPECT_LE(high.fraction, 1.0);
  uint64_t full = 0;
  for (const HNode& n : city.h.nodes()) full += n.leaf() ? n.triangles : 0;
  EXPECT_EQ(high.saved_triangles, uint64_t(std::llround(high.fraction * double(full))));
}

// An HLOD is drawn opaque: a subtree that holds glass (BLEND) must be refined, never drawn as its
// HLOD, or the glass would hide what it shows (and occlude in the OR).
TEST(LodSelect, SubtreesWithBlendedItemsAreNeverDrawnAsHlods) {
  Built b = small_city(3);
  const uint32_t glass_mesh = b.scene.objects[b.h.items()[0].object].mesh;
  Material glass;
  glass.alpha_mode = AlphaMode::Blend;
  b.scene.materials.push_back(glass);
  b.scene.meshes[glass_mesh].material = uint32_t(b.scene.materials.size() - 1);
  const uint32_t forbidden = forbid_blended_hlods(b.lod, b.scene, b.h);

  Renderables r(b.h, &b.lod);
  const Aabb all = b.h.node(0).box;
  const Camera far = Camera::look_at(all.center() + glm::dvec3(0, 0, 1e3 * all.diagonal()), all.center(), {0, 1, 0},
                                     60.0, 1.0, 0.1, 1e9);
  const LodSelector sel(r, far, 600, 1000.0);  // every existing HLOD meets this tau from there
  uint32_t expected = 0, allowed = 0;
  for (uint32_t id = 0; id < b.h.size(); ++id) {
    const HNode& n = b.h.node(id);
    if (n.leaf()) continue;
    bool holds_glass = false;  // a subtree's items are one contiguous range
    for (uint32_t i = n.first_item; i < n.first_item + n.item_count; ++i)
      holds_glass |= b.scene.objects[b.h.items()[i].object].mesh == glass_mesh;
    expected += holds_glass;
    if (holds_glass) {
      EXPECT_FALSE(sel.hlod_allowed(id)) << id;
      EXPECT_FALSE(sel.satisfies(id)) << id;
    } else if (b.lod.hlod(id)) {
      EXPECT_TRUE(sel.hlod_allowed(id)) << id;
      EXPECT_TRUE(sel.satisfies(id)) << id;
      ++allowed;
    }
  }
  EXPECT_GT(expected, 0u);
  EXPECT_EQ(forbidden, expected);
  EXPECT_GT(allowed, 0u);
}
