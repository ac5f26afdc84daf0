// Geometry resident within a budget: SceneRenderer streaming its pieces through a
// GeometryPool far smaller than the scene (so pieces are evicted and read again, and draw calls are
// cut into windows) draws the frames of the resident upload, pixel for pixel and query for query;
// the same from a scene and LODs read lazily from their caches; and --geometry-budget's values.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "common/error.hpp"
#include "common/gl/context.hpp"
#include "common/gl/scene_renderer.hpp"
#include "common/lod/lod.hpp"
#include "common/lod/lod_cache.hpp"
#include "common/scene/hierarchy.hpp"
#include "common/scene/scene_cache.hpp"
#include "common/scene/scene_io.hpp"
#include "common/setup/scene_setup.hpp"

using namespace occ;

namespace {

constexpr int kSize = 128;
constexpr uint64_t kBudget = uint64_t(384) << 10;  // plant:0.05 uploads about 3.5 MB

// Every leaf at each level, every HLOD at depth 2, and all leaves at full detail: sets of
// renderables that draw the whole upload between them.
std::vector<std::vector<uint32_t>> renderable_sets(const Hierarchy& h, const LodData& lod, const Renderables& r) {
  std::vector<std::vector<uint32_t>> sets(kLeafLodLevels + 2);
  for (uint32_t id = 0; id < h.size(); ++id) {
    if (h.node(id).leaf())
      for (uint32_t l = 0; l <= kLeafLodLevels; ++l) sets[l].push_back(r.id(id, l));
    else if (lod.hlod(id) && h.node(id).depth == 2)
      sets[kLeafLodLevels + 1].push_back(id);
  }
  return sets;
}

Camera view_of(const Scene& scene) {
  const Aabb box = scene.bounds();
  const glm::dvec3 eye(box.min.x + 3.0, 1.7, 0.0);
  return Camera::look_at(eye, eye + glm::dvec3(1, -0.1, 0.3), {0, 1, 0}, 60.0, 1.0, 0.1, 500.0);
}

// Each set drawn Shaded, as item ids, and depth-queried (the samples of the set's depth-only draws
// against the shaded frame's depth, GL_EQUAL: TwoPassDrawer's check) by both renderers: equal.
void expect_same_frames(GlContext& ctx, SceneRenderer& a, const Renderables& ra, SceneRenderer& b,
                        const Renderables& rb, const std::vector<std::vector<uint32_t>>& sets, const Camera& cam) {
  const GlApi& gl = ctx.gl();
  GLuint query = 0;
  gl.CreateQueries(GL_SAMPLES_PASSED, 1, &query);
  for (const auto& ids : sets) {
    ASSERT_FALSE(ids.empty());
    for (SceneRenderer::Mode mode : {SceneRenderer::Mode::Shaded, SceneRenderer::Mode::ItemIds}) {
      Image img[2];
      GLuint64 samples[2] = {0, 0};
      for (int k = 0; k < 2; ++k) {
        SceneRenderer& r = k ? b : a;
        if (mode == SceneRenderer::Mode::ItemIds)
          r.begin_id_frame(cam);
        else
          r.begin_frame(cam, true);
        const DrawStats st = r.draw_renderables(k ? rb : ra, ids, mode);
        EXPECT_GT(st.triangles, 0u);
        img[k] = ctx.read_rgba();
        if (mode == SceneRenderer::Mode::Shaded) {
          r.query_renderables(k ? rb : ra, ids, query, GL_EQUAL);
          gl.GetQueryObjectui64v(query, GL_QUERY_RESULT, &samples[k]);
        }
      }
      ASSERT_EQ(img[0].rgba, img[1].rgba) << "mode " << int(mode) << ", " << ids.size() << " renderables";
      EXPECT_EQ(samples[0], samples[1]) << ids.size() << " renderables";
    }
  }
  gl.DeleteQueries(1, &query);
  EXPECT_EQ(gl.GetError(), GLenum(GL_NO_ERROR));
}

}  // namespace

TEST(GeometryBudget, FlagTakesMegabytesAutoOrAllAndNamesAnythingElse) {
  SceneOptions o;
  o.geometry_budget = "all";
  EXPECT_EQ(geometry_budget_bytes(o), 0u);
  o.geometry_budget = "64";
  EXPECT_EQ(geometry_budget_bytes(o), uint64_t(64) << 20);
  o.geometry_budget = "auto";
  EXPECT_GE(geometry_budget_bytes(o), uint64_t(256) << 20);
  for (const char* bad : {"", "0", "-3", "12x", "1.5", "lots", "99999999999999999999"}) {
    o.geometry_budget = bad;
    try {
      (void)geometry_budget_bytes(o);
      ADD_FAILURE() << "accepted '" << bad << "'";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("--geometry-budget"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("'" + std::string(bad) + "'"), std::string::npos) << e.what();
    }
  }
}

// From the CPU copies (a scene larger than its budget that has no cache): the pool reads each piece
// from the arrays, which stay; far below the scene's size it evicts, reads pieces again and cuts
// draw calls, and every frame and query count equals the resident upload's.
TEST(SceneRendererStreaming, FarBelowTheScenesSizeDrawsTheResidentFrames) {
  Scene scene = load_scene("plant:0.05");
  const Hierarchy h = Hierarchy::build(scene, {});
  LodData lod = LodData::build(scene, h, {});
  auto ctx = GlContext::create(GlBackend::Auto, kSize, kSize);
  SceneRenderer a(*ctx, scene, h, &lod);
  SceneRenderer b(*ctx, scene, h, &lod, SceneRenderer::Upload{.release = true, .budget_bytes = kBudget});
  ASSERT_EQ(a.geometry_pool(), nullptr);
  const GeometryPool* pool = b.geometry_pool();
  ASSERT_NE(pool, nullptr);
  EXPECT_LE(pool->budget_bytes(), kBudget);
  EXPECT_LT(pool->capacity_bytes(), pool->budget_bytes());  // grows as frames need it
  EXPECT_GT(pool->total_bytes(), 4 * pool->capacity_bytes());
  EXPECT_FALSE(scene.geometry_released());  // streaming from the CPU copies keeps them
  EXPECT_EQ(pool->stats().uploads, 0u);     // nothing before a frame needs it

  const Renderables r(h, &lod);
  expect_same_frames(*ctx, a, r, b, r, renderable_sets(h, lod, r), view_of(scene));
  const GeometryPool::Stats& s = pool->stats();
  EXPECT_GT(s.uploads, pool->pieces());  // pieces were read again after eviction
  EXPECT_GT(s.evictions, 0u);
  EXPECT_GT(s.extra_windows, 0u);        // draw calls larger than the budget were cut
  EXPECT_LE(pool->resident_bytes(), pool->capacity_bytes());
  EXPECT_EQ(pool->capacity_bytes(), pool->budget_bytes());  // grown to the budget before evicting
  EXPECT_GT(pool->generation(), 0u);
}

// From the caches, read lazily: meshes and LODs come released with their counts and boxes, the
// arrays stay in the mapped files, and the frames equal those of the scene built in memory.
TEST(SceneRendererStreaming, LazyCachesDrawTheFramesOfTheSceneInMemory) {
  const std::string dir = testing::TempDir() + "/occ_stream_cache";
  std::filesystem::remove_all(dir);
  Scene built = load_scene("plant:0.05");
  const Hierarchy h = Hierarchy::build(built, {});
  const LodData built_lod = LodData::build(built, h, {});
  const std::string scene_path = dir + "/p.scene", lod_path = dir + "/p.lod";
  ASSERT_FALSE(save_scene_cache(scene_path, 7, built, h).has_value());
  ASSERT_FALSE(built_lod.save(lod_path).has_value());

  std::string why;
  std::optional<CachedScene> lazy = load_scene_cache(scene_path, 7, &why, 0);
  ASSERT_TRUE(lazy) << why;
  ASSERT_NE(lazy->scene.mapped, nullptr);
  ASSERT_EQ(lazy->scene.meshes.size(), built.meshes.size());
  for (size_t m = 0; m < built.meshes.size(); ++m) {
    const Mesh &l = lazy->scene.meshes[m], &b = built.meshes[m];
    EXPECT_TRUE(l.released && l.positions.empty() && l.indices.empty());
    EXPECT_EQ(l.triangle_count(), b.triangle_count());
    EXPECT_EQ(l.vertex_count(), b.vertex_count());
    EXPECT_EQ(l.box().min, b.box().min);
    EXPECT_EQ(l.box().max, b.box().max);
  }
  std::optional<LodData> lazy_lod = LodData::load(lod_path, built_lod.key(), lazy->scene, lazy->hierarchy, &why, true);
  ASSERT_TRUE(lazy_lod) << why;
  ASSERT_NE(lazy_lod->mapped(), nullptr);
  EXPECT_EQ(lazy_lod->total_triangles(), built_lod.total_triangles());
  EXPECT_EQ(lazy_lod->hash(), built_lod.hash());

  auto ctx = GlContext::create(GlBackend::Auto, kSize, kSize);
  SceneRenderer a(*ctx, built, h, &built_lod);
  // Streaming; all of it fitting the budget (uploaded at start); no budget (a tool's renderer: the
  // same, all of it read from the files at start).
  for (uint64_t budget : {kBudget, uint64_t(64) << 20, uint64_t(0)}) {
    SceneRenderer b(*ctx, lazy->scene, lazy->hierarchy, &*lazy_lod,
                    SceneRenderer::Upload{.release = true, .budget_bytes = budget});
    ASSERT_NE(b.geometry_pool(), nullptr);
    const bool fits = budget != kBudget;
    EXPECT_EQ(b.geometry_pool()->resident_bytes() == b.geometry_pool()->total_bytes(), fits);
    const Renderables ra(h, &built_lod), rb(lazy->hierarchy, &*lazy_lod);
    expect_same_frames(*ctx, a, ra, b, rb, renderable_sets(h, built_lod, ra), view_of(built));
    EXPECT_EQ(b.geometry_pool()->stats().evictions > 0, !fits);
  }

  // A lazy read does not hash the whole file; a corrupt index is caught when its mesh is read,
  // naming the file and the mesh, before anything is drawn with it.
  {
    std::fstream f(scene_path, std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(std::streamoff(lazy->scene.mapped->meshes[0].indices.offset + 3));
    f.put(char(0x7f));
  }
  lazy_lod.reset();
  lazy.reset();
  lazy = load_scene_cache(scene_path, 7, &why, 0);
  ASSERT_TRUE(lazy) << why;
  EXPECT_FALSE(load_scene_cache(scene_path, 7, &why).has_value());  // read whole: the checksum
  EXPECT_NE(why.find("checksum"), std::string::npos) << why;
  SceneRenderer c(*ctx, lazy->scene, lazy->hierarchy, nullptr, SceneRenderer::Upload{.budget_bytes = kBudget});
  std::vector<uint32_t> items;
  for (uint32_t i = 0; i < lazy->hierarchy.items().size(); ++i)
    if (lazy->scene.objects[lazy->hierarchy.items()[i].object].mesh == 0) items.push_back(i);
  ASSERT_FALSE(items.empty());
  c.begin_frame(view_of(built), true);
  try {
    c.draw_items(items, SceneRenderer::Mode::Shaded);
    ADD_FAILURE() << "drew a mesh with an index out of range";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("mesh 0: index"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("corrupt"), std::string::npos) << e.what();
  }
  std::filesystem::remove_all(dir);
}

// A budget too small for one piece says so (and which flag to change) instead of drawing less.
TEST(SceneRendererStreaming, BudgetSmallerThanOnePieceIsAnErrorNamingTheFlag) {
  Scene scene = load_scene("plant:0.05");
  const Hierarchy h = Hierarchy::build(scene, {});
  auto ctx = GlContext::create(GlBackend::Auto, kSize, kSize);
  SceneRenderer b(*ctx, scene, h, nullptr, SceneRenderer::Upload{.budget_bytes = 1024});
  std::vector<uint32_t> items(h.items().size());
  for (uint32_t i = 0; i < items.size(); ++i) items[i] = i;
  b.begin_frame(view_of(scene), true);
  try {
    b.draw_items(items, SceneRenderer::Mode::Shaded);
    ADD_FAILURE() << "drew with a 1 KiB budget";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("--geometry-budget"), std::string::npos) << e.what();
  }
}
