// SceneRenderer and BoxQuerier on tiny hand-made scenes with known screen positions.
// Camera at the eye looking down -Z, 60 degrees vertical fov, square 128 x 128 viewport: at
// distance d the view spans +-d*tan(30 deg) = +-0.577 d.
#include <gtest/gtest.h>

#include <numeric>

#include <glm/gtc/matrix_transform.hpp>

#include "common/gl/box_query.hpp"
#include "common/gl/context.hpp"
#include "common/gl/scene_renderer.hpp"
#include "common/scene/hierarchy.hpp"
#include "common/lod/lod.hpp"
#include "common/scene/scene_io.hpp"

namespace occ {
inline void PrintTo(GlBackend b, std::ostream* os) {
  *os << (b == GlBackend::Egl ? "egl" : b == GlBackend::OSMesa ? "osmesa" : "auto");
}
}  // namespace occ

using namespace occ;

namespace {

constexpr int kSize = 128;

// Unit quad in the XY plane, centred on the origin, facing +Z; `res` x `res` cells.
Mesh quad_mesh(int res = 1) {
  Mesh m;
  for (int y = 0; y <= res; ++y)
    for (int x = 0; x <= res; ++x) m.positions.push_back({float(x) / res - 0.5f, float(y) / res - 0.5f, 0.0f});
  for (int y = 0; y < res; ++y)
    for (int x = 0; x < res; ++x) {
      uint32_t a = y * (res + 1) + x, b = a + 1, c = a + res + 1, d = c + 1;
      m.indices.insert(m.indices.end(), {a, b, d, a, d, c});
    }
  compute_normals(m);
  return m;
}

glm::dmat4 place(glm::dvec3 at, double scale = 1.0) {
  return glm::scale(glm::translate(glm::dmat4(1.0), at), glm::dvec3(scale));
}

// Two unit quads 4 m in front of the eye, left (x = -1) and right (x = +1), shifted by `offset`.
Scene two_quads(glm::dvec3 offset = glm::dvec3(0.0), int res = 1) {
  Scene s;
  s.meshes.push_back(quad_mesh(res));
  s.objects.push_back({0, place(offset + glm::dvec3(-1, 0, -4)), "left"});
  s.objects.push_back({0, place(offset + glm::dvec3(1, 0, -4)), "right"});
  return s;
}

Camera camera_at(glm::dvec3 eye) {
  return Camera::look_at(eye, eye + glm::dvec3(0, 0, -1), {0, 1, 0}, 60.0, 1.0, 0.1, 100.0);
}

std::array<uint8_t, 4> pixel(const Image& img, int x, int y) {
  const uint8_t* p = &img.rgba[(size_t(y) * img.width + x) * 4];
  return {p[0], p[1], p[2], p[3]};
}

std::vector<uint32_t> all_items(const Hierarchy& h) {
  std::vector<uint32_t> v(h.items().size());
  std::iota(v.begin(), v.end(), 0u);
  return v;
}

Image render_shaded(GlContext& ctx, Scene scene, const Camera& cam) {
  Hierarchy h = Hierarchy::build(scene, {});
  SceneRenderer r(ctx, scene, h);
  r.begin_frame(cam, true);
  r.draw_items(all_items(h), SceneRenderer::Mode::Shaded);
  return ctx.read_rgba();
}

class SceneRendererBackend : public testing::TestWithParam<GlBackend> {};

}  // namespace

TEST_P(SceneRendererBackend, ShadesObjectsWhereTheyProjectAndLeavesBackground) {
  auto ctx = GlContext::create(GetParam(), kSize, kSize);
  Scene scene = two_quads();
  Hierarchy h = Hierarchy::build(scene, {});
  SceneRenderer r(*ctx, scene, h);
  r.begin_frame(camera_at({0, 0, 0}), true);
  DrawStats st = r.draw_items(all_items(h), SceneRenderer::Mode::Shaded);
  EXPECT_EQ(st.items, 2u);
  EXPECT_EQ(st.triangles, 4u);
  Image img = ctx->read_rgba();
  // Left quad covers columns ~22..50, right ~78..106, rows ~50..78; the centre is a gap.
  const auto bg = SceneRenderer::kBackgroundRgba8;
  for (auto [x, y] : {std::pair{64, 64}, {5, 5}, {36, 40}, {36, 88}, {120, 64}})
    EXPECT_EQ(pixel(img, x, y), bg) << "at " << x << "," << y;
  const auto left = pixel(img, 36, 64), right = pixel(img, 92, 64);
  EXPECT_NE(left, bg);
  EXPECT_NE(right, bg);
  EXPECT_NE(left, right) << "objects get distinct base colours";
  EXPECT_EQ(left[3], 255);
  // Facing the headlight: bright (base colour >= 0.45, lit >= 0.9 at this angle).
  for (int c = 0; c < 3; ++c) EXPECT_GT(left[c], 90);
  EXPECT_EQ(ctx->gl().GetError(), GLenum(GL_NO_ERROR));
}

TEST_P(SceneRendererBackend, FarFromOriginRendersTheSamePixels) {
  auto ctx = GlContext::create(GetParam(), kSize, kSize);
  const glm::dvec3 far(1e7, -3e6, 1e7);
  Image near_img = render_shaded(*ctx, two_quads(), camera_at({0.1, 0.2, 0}));
  Image far_img = render_shaded(*ctx, two_quads(far), camera_at(far + glm::dvec3(0.1, 0.2, 0)));
  EXPECT_EQ(near_img.rgba, far_img.rgba);
}

INSTANTIATE_TEST_SUITE_P(Backends, SceneRendererBackend, testing::Values(GlBackend::Egl, GlBackend::OSMesa),
                         [](const auto& info) { return info.param == GlBackend::Egl ? "Egl" : "OSMesa"; });

TEST(SceneRenderer, ClusteredItemsAndWholeNodesDrawTheSameImage) {
  auto ctx = GlContext::create(GlBackend::Auto, kSize, kSize);
  Scene scene = two_quads({}, 16);  // 512 triangles per quad, split into 32-triangle items
  BuildParams params;
  params.cluster_triangles = 32;
  Hierarchy h = Hierarchy::build(scene, params);
  ASSERT_EQ(h.items().size(), 32u);
  SceneRenderer r(*ctx, scene, h);
  const Camera cam = camera_at({0, 0, 0});
  r.begin_frame(cam, true);
  r.draw_items(all_items(h), SceneRenderer::Mode::Shaded);
  Image by_items = ctx->read_rgba();
  r.begin_frame(cam, true);
  const uint32_t root = 0;
  DrawStats st = r.draw_nodes({&root, 1}, SceneRenderer::Mode::Shaded);
  EXPECT_EQ(st.items, 32u);
  EXPECT_EQ(st.triangles, 1024u);
  EXPECT_EQ(by_items.rgba, ctx->read_rgba().rgba);
  EXPECT_NE(pixel(by_items, 36, 64), SceneRenderer::kBackgroundRgba8);
  const uint32_t bad = 32;
  EXPECT_THROW(r.draw_items({&bad, 1}, SceneRenderer::Mode::Shaded), std::out_of_range);
}

TEST(SceneRenderer, ItemBufferShowsOnlyUnoccludedItems) {
  auto ctx = GlContext::create(GlBackend::Auto, kSize, kSize);
  Scene scene = two_quads();
  // A third, larger quad right behind the left one: hidden except around the left quad.
  scene.objects.push_back({0, place({-1, 0, -5}, 1.1), "behind-left"});
  // A fourth quad hidden completely behind the right one.
  scene.objects.push_back({0, place({1, 0, -6}, 0.5), "hidden"});
  Hierarchy h = Hierarchy::build(scene, {});
  SceneRenderer r(*ctx, scene, h);
  r.begin_id_frame(camera_at({0, 0, 0}));
  r.draw_items(all_items(h), SceneRenderer::Mode::ItemIds);
  std::vector<uint32_t> seen_objects;
  for (uint32_t item : ids_in_image(ctx->read_rgba())) seen_objects.push_back(h.items()[item].object);
  std::sort(seen_objects.begin(), seen_objects.end());
  EXPECT_EQ(seen_objects, (std::vector<uint32_t>{0, 1, 2}));

  // The root node's id everywhere something is drawn.
  r.begin_id_frame(camera_at({0, 0, 0}));
  const uint32_t root = 0;
  r.draw_nodes_ids({&root, 1});
  EXPECT_EQ(ids_in_image(ctx->read_rgba()), std::vector<uint32_t>{0});
}

TEST(SceneRenderer, DepthOnlyWritesDepthButNoColour) {
  auto ctx = GlContext::create(GlBackend::Auto, kSize, kSize);
  Scene scene = two_quads();
  Hierarchy h = Hierarchy::build(scene, {});
  SceneRenderer r(*ctx, scene, h);
  r.begin_frame(camera_at({0, 0, 0}), true);
  r.draw_items(all_items(h), SceneRenderer::Mode::DepthOnly);
  Image img = ctx->read_rgba();
  EXPECT_EQ(pixel(img, 36, 64), SceneRenderer::kBackgroundRgba8);
  // Shading the same items afterwards: equal depth fails GL_GREATER, nothing new is drawn.
  r.draw_items(all_items(h), SceneRenderer::Mode::Shaded);
  EXPECT_EQ(ctx->read_rgba().rgba, img.rgba);
}

namespace {

// A 4 x 4 m occluder 5 m in front of the eye, rendered depth-only.
struct OccluderFixture {
  std::unique_ptr<GlContext> ctx = GlContext::create(GlBackend::Auto, kSize, kSize);
  Scene scene;
  Hierarchy h;
  std::unique_ptr<SceneRenderer> renderer;
  Camera cam;

  explicit OccluderFixture(glm::dvec3 offset) : cam(camera_at(offset)) {
    scene.meshes.push_back(quad_mesh());
    scene.objects.push_back({0, place(offset + glm::dvec3(0, 0, -5), 4.0), "occluder"});
    h = Hierarchy::build(scene, {});
    renderer = std::make_unique<SceneRenderer>(*ctx, scene, h);
    renderer->begin_frame(cam, true);
    renderer->draw_items(all_items(h), SceneRenderer::Mode::DepthOnly);
  }
};

Aabb box_at(glm::dvec3 offset, glm::dvec3 lo, glm::dvec3 hi) { return Aabb{offset + lo, offset + hi}; }

class BoxQuerierOffset : public testing::TestWithParam<double> {};

}  // namespace

TEST_P(BoxQuerierOffset, BoxBehindOccluderHasNoSamplesBesideAndInFrontHave) {
  const glm::dvec3 offset(GetParam(), GetParam(), -GetParam());
  OccluderFixture f(offset);
  const Image before = f.ctx->read_rgba();
  BoxQuerier q(*f.ctx);
  q.begin(f.cam);
  // Issue the whole batch first, then read (the batched use).
  uint32_t behind = q.issue(box_at(offset, {-0.5, -0.5, -8}, {0.5, 0.5, -7}));
  uint32_t beside = q.issue(box_at(offset, {3, -0.5, -8}, {4, 0.5, -7}));
  uint32_t in_front = q.issue(box_at(offset, {-0.5, -0.5, -3}, {0.5, 0.5, -2}));
  uint32_t occluder_itself = q.issue(f.h.items()[0].box);  // flat box on the depth it wrote
  uint32_t empty = q.issue(Aabb{});
  EXPECT_EQ(q.result(behind), 0u);
  EXPECT_GT(q.result(beside), 0u);
  // In front: its silhouette is the 1 x 1 m face at 2 m, (0.5 / (2 * 0.577) * 128)^2 = 3072
  // pixels, and every silhouette pixel passes once: back faces are culled, front faces cover it.
  EXPECT_NEAR(double(q.result(in_front)), 3072.0, 150.0);
  EXPECT_GT(q.result(occluder_itself), 0u) << "the relative pad keeps flat boxes conservative";
  EXPECT_EQ(q.result(empty), 0u);
  EXPECT_EQ(q.queries_issued(), 5u);
  q.end_batch();
  EXPECT_THROW(q.result(0), std::out_of_range);
  // Recycled handles work again in the next batch.
  uint32_t again = q.issue(box_at(offset, {-0.5, -0.5, -8}, {0.5, 0.5, -7}));
  EXPECT_EQ(again, 0u);
  EXPECT_EQ(q.result(again), 0u);
  q.end();
  EXPECT_EQ(f.ctx->read_rgba().rgba, before.rgba) << "queries write no colour";
  EXPECT_EQ(f.ctx->gl().GetError(), GLenum(GL_NO_ERROR));
}

INSTANTIATE_TEST_SUITE_P(NearAndFarFromOrigin, BoxQuerierOffset, testing::Values(0.0, 1e7),
                         [](const auto& info) { return info.param == 0.0 ? "AtOrigin" : "At1e7"; });

TEST(BoxQuerier, EyeInsideBoxCountsTheViewportWithoutDrawing) {
  // The visible occluder lies inside the box, and every box face the eye can see is behind it: a
  // query drawn would count nothing. A padded box within reach of the near rectangle is not drawn
  // and counts the viewport's pixels (box_query.hpp), in a batch too; the traversal decides the
  // unpadded box on the CPU first (visible_without_query).
  OccluderFixture f(glm::dvec3(0.0));
  Scene big;
  big.meshes.push_back(quad_mesh());
  big.objects.push_back({0, place({0, 0, -5}, 8.0), "wall filling the view"});
  Hierarchy h = Hierarchy::build(big, {});
  SceneRenderer r(*f.ctx, big, h);
  r.begin_frame(f.cam, true);
  r.draw_items(all_items(h), SceneRenderer::Mode::DepthOnly);
  BoxQuerier q(*f.ctx);
  q.begin(f.cam);
  const Aabb around_eye{glm::dvec3(-10), glm::dvec3(10)};
  ASSERT_TRUE(around_eye.contains(f.cam.eye));
  const uint64_t viewport = uint64_t(f.ctx->width()) * uint64_t(f.ctx->height());
  const uint32_t handle = q.issue(around_eye);
  EXPECT_TRUE(q.ready(handle));
  EXPECT_EQ(q.result(handle), viewport);
  EXPECT_EQ(q.queries_issued(), 1u);
  q.reset();
  q.end();
  for (bool exact : {false, true}) {
    BoxBatchCounter batch(*f.ctx, exact);
    batch.begin(f.cam);
    EXPECT_EQ(batch.result(batch.issue(around_eye)), exact ? viewport : 1u);
    batch.end();
  }
  EXPECT_TRUE(visible_without_query(around_eye, f.cam));
}

// The geometry goes to GL in small segments (hundreds here) and, with Upload::release,
// the CPU arrays are freed as they go. The frames (full detail, leaf LODs, HLODs, item ids) must
// be those of the default upload, and what culling needs must survive the release.
TEST(SceneRenderer, StreamedUploadWithReleaseDrawsTheSameFramesAndFreesTheArrays) {
  Scene kept = load_scene("plant:0.05");
  const Hierarchy h = Hierarchy::build(kept, {});
  const LodData kept_lod = LodData::build(kept, h, {});
  Scene freed = kept;
  LodData freed_lod = kept_lod;
  auto ctx = GlContext::create(GlBackend::Auto, kSize, kSize);
  SceneRenderer a(*ctx, kept, h, &kept_lod);
  SceneRenderer b(*ctx, freed, h, &freed_lod, SceneRenderer::Upload{.segment_bytes = 4096, .release = true});

  for (const Mesh& m : freed.meshes) {
    EXPECT_TRUE(m.released);
    EXPECT_TRUE(m.positions.empty() && m.normals.empty() && m.indices.empty());
    EXPECT_EQ(m.positions.capacity() + m.indices.capacity(), 0u);
  }
  for (size_t i = 0; i < kept.meshes.size(); ++i) {
    EXPECT_EQ(freed.meshes[i].triangle_count(), kept.meshes[i].triangle_count());
    EXPECT_EQ(freed.meshes[i].box().min, kept.meshes[i].box().min);
    EXPECT_EQ(freed.meshes[i].box().max, kept.meshes[i].box().max);
  }
  EXPECT_EQ(freed.triangle_count(), kept.triangle_count());
  EXPECT_TRUE(freed_lod.geometry_released());
  EXPECT_FALSE(kept_lod.geometry_released());
  EXPECT_EQ(freed_lod.total_triangles(), kept_lod.total_triangles());
  for (const LodMesh& m : freed_lod.hlods()) EXPECT_TRUE(m.indices.empty());
  EXPECT_THROW((void)freed.content_hash(), std::logic_error);
  EXPECT_THROW(SceneRenderer(*ctx, freed, h), std::logic_error);  // nothing left to upload
  EXPECT_TRUE(freed_lod.save(testing::TempDir() + "/released.lod").has_value());  // refuses

  const Renderables ra(h, &kept_lod), rb(h, &freed_lod);
  for (uint32_t r = 0; r < ra.count(); ++r) ASSERT_EQ(ra.triangles(r), rb.triangles(r)) << r;
  // Every leaf at each level, and every HLOD: the whole LOD upload is drawn.
  std::vector<std::vector<uint32_t>> sets(kLeafLodLevels + 2);
  for (uint32_t id = 0; id < h.size(); ++id) {
    if (h.node(id).leaf())
      for (uint32_t l = 0; l <= kLeafLodLevels; ++l) sets[l].push_back(ra.id(id, l));
    else if (kept_lod.hlod(id) && h.node(id).depth == 2)
      sets[kLeafLodLevels + 1].push_back(id);
  }
  ASSERT_FALSE(sets.back().empty());
  const Aabb box = kept.bounds();
  const glm::dvec3 eye(box.min.x + 3.0, 1.7, 0.0);
  const Camera cam = Camera::look_at(eye, eye + glm::dvec3(1, -0.1, 0.3), {0, 1, 0}, 60.0, 1.0, 0.1, 500.0);
  for (const auto& ids : sets) {
    for (SceneRenderer::Mode mode : {SceneRenderer::Mode::Shaded, SceneRenderer::Mode::ItemIds}) {
      Image img[2];
      for (int k = 0; k < 2; ++k) {
        SceneRenderer& r = k ? b : a;
        if (mode == SceneRenderer::Mode::ItemIds)
          r.begin_id_frame(cam);
        else
          r.begin_frame(cam, true);
        const DrawStats st = r.draw_renderables(k ? rb : ra, ids, mode);
        EXPECT_GT(st.triangles, 0u);
        img[k] = ctx->read_rgba();
      }
      ASSERT_EQ(img[0].rgba, img[1].rgba) << "mode " << int(mode) << ", " << ids.size() << " renderables";
      if (mode == SceneRenderer::Mode::Shaded) {
        size_t drawn = 0;
        for (size_t p = 0; p < img[0].rgba.size(); p += 4)
          drawn += pixel(img[0], int(p / 4 % kSize), int(p / 4 / kSize)) != SceneRenderer::kBackgroundRgba8;
        EXPECT_GT(drawn, size_t(kSize));  // the frame shows the plant, not just background
      }
    }
  }
}

// Flushing in the middle of a frame (set_flush_triangles: indirect draws cut into parts, glFlush
// between them) changes nothing drawn: every part size gives the frame of no flushes, draw for draw.
TEST(SceneRenderer, FlushingEveryFewTrianglesDrawsTheSameFrames) {
  Scene scene = load_scene("plant:0.05");
  const Hierarchy h = Hierarchy::build(scene, {});
  auto ctx = GlContext::create(GlBackend::Auto, kSize, kSize);
  SceneRenderer r(*ctx, scene, h, nullptr, SceneRenderer::Upload{.segment_bytes = 1 << 16});
  const Aabb box = scene.bounds();
  const glm::dvec3 eye(box.min.x + 3.0, 1.7, 0.0);
  const Camera cam = Camera::look_at(eye, eye + glm::dvec3(1, -0.1, 0.3), {0, 1, 0}, 60.0, 1.0, 0.1, 500.0);
  const std::vector<uint32_t> items = all_items(h);
  for (SceneRenderer::Mode mode : {SceneRenderer::Mode::Shaded, SceneRenderer::Mode::ItemIds}) {
    Image first;
    DrawStats first_stats;
    // nullopt: automatic part sizes (FlushSchedule::part_of).
    for (std::optional<uint32_t> flush : {std::optional<uint32_t>(0u), {1u}, {97u}, {5000u},
                                          {FlushSchedule::kMaxPart}, std::optional<uint32_t>()}) {
      if (flush)
        r.set_flush_triangles(*flush);
      else
        r.set_flush_automatic();
      if (mode == SceneRenderer::Mode::ItemIds)
        r.begin_id_frame(cam);
      else
        r.begin_frame(cam, true);
      const DrawStats st = r.draw_items(items, mode);
      const Image img = ctx->read_rgba();
      if (flush == 0) {
        first = img;
        first_stats = st;
        EXPECT_GT(st.triangles, 10000u);  // several parts at the default size
        EXPECT_GT(ids_in_image(img).size(), 10u);
        continue;
      }
      EXPECT_EQ(st.items, first_stats.items);
      EXPECT_EQ(st.triangles, first_stats.triangles);
      ASSERT_EQ(img.rgba, first.rgba) << "mode " << int(mode) << ", flush every "
                                      << (flush ? std::to_string(*flush) : std::string("automatic")) << " triangles";
    }
  }
}

// Automatic part sizes: an eighth of the draw call, never below kMinPart (a flush costs
// llvmpipe a scene of its own) nor above kMaxPart.
TEST(SceneRenderer, AutomaticFlushPartsAreAnEighthOfTheCallWithinBounds) {
  EXPECT_EQ(FlushSchedule::part_of(0), FlushSchedule::kMinPart);
  EXPECT_EQ(FlushSchedule::part_of(7200), FlushSchedule::kMinPart);    // the duplex's V
  EXPECT_EQ(FlushSchedule::part_of(32000), 4000u);                      // its frustum set
  EXPECT_EQ(FlushSchedule::part_of(198000), FlushSchedule::kMaxPart);  // the whole saw
  EXPECT_EQ(FlushSchedule::part_of(uint64_t(1) << 40), FlushSchedule::kMaxPart);
  for (uint64_t t = 0; t < 400000; t += 1237) {
    const uint32_t part = FlushSchedule::part_of(t);
    EXPECT_GE(part, FlushSchedule::kMinPart);
    EXPECT_LE(part, FlushSchedule::kMaxPart);
    if (part > FlushSchedule::kMinPart && part < FlushSchedule::kMaxPart) {
      EXPECT_EQ(part, t / FlushSchedule::kParts);
    }
  }
}

// The schedule alone: a part is full when the triangles submitted since the last flush reach
// it; requests change the part size, not the count; 0 never flushes; queries use the fixed size
// (kMaxPart when automatic).
TEST(FlushSchedule, CutsCallsIntoPartsAndFlushesWhenAPartIsFull) {
  FlushSchedule s;
  EXPECT_EQ(s.fixed(), std::optional<uint32_t>(FlushSchedule::kMaxPart));
  s.request(100u);
  s.begin_call(1000);
  EXPECT_TRUE(s.fits(99));
  EXPECT_FALSE(s.fits(100));
  EXPECT_FALSE(s.submitted(60));
  EXPECT_TRUE(s.fits(39));
  EXPECT_FALSE(s.fits(40));
  EXPECT_TRUE(s.submitted(50));  // 110: flush, the count starts again
  EXPECT_TRUE(s.fits(99));
  EXPECT_FALSE(s.submitted(30));
  s.request(std::nullopt);  // automatic: an eighth of the call
  EXPECT_EQ(s.fixed(), std::nullopt);
  s.begin_call(32000);
  EXPECT_TRUE(s.fits(3969));  // 30 still counted
  EXPECT_FALSE(s.fits(3970));
  s.begin_queries();
  EXPECT_TRUE(s.fits(FlushSchedule::kMaxPart - 31));
  EXPECT_FALSE(s.fits(FlushSchedule::kMaxPart - 30));
  s.request(0u);
  s.begin_call(1);
  EXPECT_TRUE(s.fits(uint64_t(1) << 40));
  EXPECT_FALSE(s.submitted(uint64_t(1) << 40));
}

// The plant's solids are closed with outward faces (plant.hpp), so culling their back faces (its
// single-sided material) hides nothing the double-sided drawing shows: from cameras along the walk
// and looking across the bays, all but a few pixels (slits between abutting faces, sub-pixel
// ends of thin open tubes) are equal. A mesh wound inside out would lose all its front pixels.
TEST(SceneRenderer, PlantSolidsLookTheSameWithBackFacesCulled) {
  Scene single = load_scene("plant:0.3");
  ASSERT_EQ(single.materials.size(), 1u);
  EXPECT_FALSE(single.materials[0].double_sided);
  for (const Mesh& m : single.meshes) ASSERT_EQ(m.material, 0u) << m.name;
  Scene both = single;
  both.materials[0].double_sided = true;
  auto ctx = GlContext::create(GlBackend::Auto, kSize, kSize);
  const Aabb box = single.bounds();
  size_t differing = 0, shown = 0, frames = 0;
  for (double t : {0.1, 0.4, 0.7}) {
    const glm::dvec3 eye(box.min.x + t * (box.max.x - box.min.x), 1.7 + 8.0 * t, 0.0);
    for (const glm::dvec3 dir : {glm::dvec3(1, -0.05, 0), glm::dvec3(0.3, 0.1, 1), glm::dvec3(-0.2, 0.3, -1)}) {
      const Camera cam = Camera::look_at(eye, eye + dir, {0, 1, 0}, 60.0, 1.0, 0.1, 500.0);
      const Image a = render_shaded(*ctx, single, cam), b = render_shaded(*ctx, both, cam);
      ASSERT_EQ(a.rgba.size(), b.rgba.size());
      for (size_t i = 0; i < a.rgba.size(); i += 4) {
        differing += !std::equal(&a.rgba[i], &a.rgba[i] + 3, &b.rgba[i]);
        shown += b.rgba[i] || b.rgba[i + 1] || b.rgba[i + 2];
      }
      ++frames;
    }
  }
  const size_t pixels = frames * size_t(kSize) * kSize;
  std::cout << "plant single- vs double-sided: " << differing << " of " << pixels << " pixels differ\n";
  EXPECT_GT(shown, pixels / 2);             // the views show the plant
  EXPECT_LT(differing, pixels / 1000 + 1);  // at most 0.1 %
}

// The exact count's glass (reference --exact): a BLEND item counts as shown when it passes the
// depth test against the opaque depth, as the Shaded pass draws it. Glass in front of a wall and
// glass beside it show; glass behind the wall does not; an opaque item is refused.
TEST(SceneRenderer, BlendedItemsShowOnlyWhereTheyAreInFrontOfOpaqueDepth) {
  auto ctx = GlContext::create(GlBackend::Auto, kSize, kSize);
  Scene scene;
  scene.meshes.push_back(quad_mesh());  // opaque: no material
  scene.meshes.push_back(quad_mesh());
  scene.materials.push_back({.name = "glass", .base_color = {0.2f, 0.4f, 1.0f, 0.5f}, .alpha_mode = AlphaMode::Blend,
                             .double_sided = true});
  scene.meshes[1].material = 0;
  scene.objects.push_back({0, place({0, 0, -4}, 2.0), "wall"});
  scene.objects.push_back({1, place({0, 0, -3}, 0.5), "glass in front"});
  scene.objects.push_back({1, place({0, 0, -6}, 0.5), "glass behind"});
  scene.objects.push_back({1, place({2.5, 0, -6}, 0.5), "glass beside"});
  const Hierarchy h = Hierarchy::build(scene, {});
  SceneRenderer r(*ctx, scene, h);
  ASSERT_TRUE(r.has_blended());
  std::vector<uint32_t> glass;
  std::vector<std::string> names;
  for (uint32_t i = 0; i < h.items().size(); ++i) {
    const uint32_t object = h.items()[i].object;
    EXPECT_EQ(r.item_blended(i), scene.objects[object].mesh == 1) << scene.objects[object].name;
    if (r.item_blended(i)) {
      glass.push_back(i);
      names.push_back(scene.objects[object].name);
    }
  }
  ASSERT_EQ(glass.size(), 3u);
  r.begin_id_frame(camera_at({0, 0, 0}));
  r.draw_items(all_items(h), SceneRenderer::Mode::ItemIds);
  EXPECT_EQ(ids_in_image(ctx->read_rgba()).size(), 1u);  // the wall only: glass is not in the item buffer
  std::vector<GLuint> queries(glass.size());
  ctx->gl().CreateQueries(GL_SAMPLES_PASSED, GLsizei(queries.size()), queries.data());
  r.query_blended_items(glass, queries);
  for (size_t k = 0; k < glass.size(); ++k) {
    GLuint64 samples = 0;
    ctx->gl().GetQueryObjectui64v(queries[k], GL_QUERY_RESULT, &samples);
    EXPECT_EQ(samples > 0, names[k] != "glass behind") << names[k] << ": " << samples << " samples";
  }
  ctx->gl().DeleteQueries(GLsizei(queries.size()), queries.data());
  uint32_t wall_item = 0;
  while (r.item_blended(wall_item)) ++wall_item;
  const uint32_t bad[] = {wall_item};
  const GLuint q[] = {0};
  EXPECT_THROW(r.query_blended_items(bad, q), std::invalid_argument);
}

// glTF requires flat normals for a primitive without NORMAL (Mesh::flat): a cube on 8 shared
// vertices, shaded flat, looks like the cube on 24 vertices that carry each face's normal, and
// not like its smooth normals (the corners' averages), which shade each face in a gradient.
TEST(SceneRenderer, FlatMeshesShadeEachTriangleWithItsOwnNormal) {
  const std::vector<glm::vec3> corner{{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0},
                                      {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
  const std::vector<uint32_t> faces{0, 2, 1, 0, 3, 2, 4, 5, 6, 4, 6, 7, 0, 1, 5, 0, 5, 4,
                                    3, 6, 2, 3, 7, 6, 0, 4, 7, 0, 7, 3, 1, 2, 6, 1, 6, 5};
  auto scene_of = [](Mesh m) {
    Scene s;
    s.meshes.push_back(std::move(m));
    s.objects.push_back({0, place({-0.5, -0.5, -0.5}), "cube"});
    return s;
  };
  Mesh shared;  // 8 vertices, smooth normals
  shared.positions = corner;
  shared.indices = faces;
  compute_normals(shared);
  Mesh flat = shared;
  flat.flat = true;
  Mesh faceted;  // every triangle on its own vertices, with its face's normal
  for (size_t t = 0; t < faces.size(); t += 3) {
    const glm::vec3 a = corner[faces[t]], b = corner[faces[t + 1]], c = corner[faces[t + 2]];
    const glm::vec3 n = glm::normalize(glm::cross(b - a, c - a));
    for (const glm::vec3& p : {a, b, c}) {
      faceted.indices.push_back(uint32_t(faceted.positions.size()));
      faceted.positions.push_back(p);
      faceted.normals.push_back(n);
    }
  }
  auto ctx = GlContext::create(GlBackend::Auto, kSize, kSize);
  size_t shown = 0, off_faceted = 0, off_smooth = 0;
  for (const glm::dvec3 eye : {glm::dvec3(1.8, 1.3, 2.2), glm::dvec3(-2.5, -0.7, 1.1), glm::dvec3(0.4, 2.9, -1.6)}) {
    const Camera cam = Camera::look_at(eye, glm::dvec3(0.0), {0, 1, 0}, 60.0, 1.0, 0.1, 100.0);
    const Image a = render_shaded(*ctx, scene_of(flat), cam), b = render_shaded(*ctx, scene_of(faceted), cam),
                c = render_shaded(*ctx, scene_of(shared), cam);
    for (size_t i = 0; i < a.rgba.size(); i += 4) {
      const bool on = !std::equal(&b.rgba[i], &b.rgba[i] + 3, &b.rgba[0]);  // not the corner's background
      shown += on;
      int worst_b = 0, worst_c = 0;
      for (int k = 0; k < 3; ++k) {
        worst_b = std::max(worst_b, std::abs(int(a.rgba[i + k]) - int(b.rgba[i + k])));
        worst_c = std::max(worst_c, std::abs(int(a.rgba[i + k]) - int(c.rgba[i + k])));
      }
      off_faceted += worst_b > 1;  // a level of rounding: derivatives against a given normal
      off_smooth += on && worst_c > 8;
    }
  }
  std::cout << "flat cube: " << shown << " pixels shown, " << off_faceted << " off the faceted cube's by more than 1, "
            << off_smooth << " off the smooth one's by more than 8\n";
  EXPECT_GT(shown, 3u * 1000);
  EXPECT_EQ(off_faceted, 0u);
  EXPECT_GT(off_smooth, shown / 5);
}
