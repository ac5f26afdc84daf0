// The OR on the CPU (common/cull/depth_raster.hpp) against llvmpipe's own depth of the same
// occluders: its depth is never nearer than GL's, it covers nearly all GL covers (walks through
// walls included: triangles across the near plane, corners far off screen), and a leaf it finds
// hidden by its own triangles passes no sample of GL's occlusion query of those triangles (what
// the render client's frame would show of it).
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <memory>
#include <stdexcept>

#include "common/camera_path.hpp"
#include "common/cull/depth_raster.hpp"
#include "common/cull/raster_queries.hpp"
#include "common/gl/box_query.hpp"
#include "common/gl/context.hpp"
#include "common/gl/scene_renderer.hpp"
#include "common/lod/lod_select.hpp"
#include "common/scene/hierarchy.hpp"
#include "common/scene/scene_io.hpp"

using namespace occ;

namespace {
// A shared real scene where ../shared is beside the checkout, else "".
std::string shared_scene(const std::string& rel) {
  const std::string p = std::string(OCC_SHARED_DIR) + "/scenes/" + rel;
  return std::filesystem::exists(p) ? p : "";
}

// One scene twice: on the CPU (CpuOccluders) and in GL without the occluder offset (the depth of
// the render client's frame, what HC's answers must hold for; the switch nodes' OR moves its
// occluders back further), with an occlusion query and the scene's non-empty leaves.
struct CpuAndGl {
  Scene scene;
  Hierarchy h;
  std::optional<CpuOccluders> cpu;
  std::unique_ptr<GlContext> ctx;
  std::unique_ptr<SceneRenderer> renderer;
  std::unique_ptr<Renderables> r;
  GLuint query = 0;
  std::vector<uint32_t> leaves;

  CpuAndGl(const std::string& spec, Viewport vp) : scene(load_scene(spec)), h(Hierarchy::build(scene, {})) {
    std::string why;
    cpu = CpuOccluders::copy(scene, h, vp.width, vp.height, &why);
    if (!cpu) throw std::runtime_error(spec + ": " + why);
    ctx = GlContext::create(GlBackend::Auto, vp.width, vp.height);
    renderer = std::make_unique<SceneRenderer>(*ctx, scene, h);
    r = std::make_unique<Renderables>(h, nullptr);
    ctx->gl().CreateQueries(GL_SAMPLES_PASSED, 1, &query);
    for (uint32_t id = 0; id < h.size(); ++id)
      if (h.node(id).leaf() && h.node(id).item_count > 0) leaves.push_back(id);
  }
  ~CpuAndGl() { ctx->gl().DeleteQueries(1, &query); }

  // Samples of leaf `id`'s triangles passing GL's depth test over GL's depth buffer.
  uint64_t samples(uint32_t id) {
    const uint32_t ids[1] = {id};
    renderer->query_renderables(*r, ids, query, GL_GREATER);
    GLuint64 n = 0;
    ctx->gl().GetQueryObjectui64v(query, GL_QUERY_RESULT, &n);
    return n;
  }
};
}  // namespace

TEST(CpuOr, NeverNearerThanGlAndHidesOnlyWhatGlHides) {
  std::vector<std::pair<std::string, std::string>> views = {
      {"office", "walk:6"}, {"city:8x8:3:10:1", "walk:6"}, {"hard:cracks", "walk:6"}, {"plant:0.05", "walk:6"}, {"pipes", "orbit:6"}};
  for (const char* rel : {"2CylinderEngine/2CylinderEngine.gltf", "ReciprocatingSaw/ReciprocatingSaw.gltf"})
    if (std::string p = shared_scene(rel); !p.empty()) views.push_back({p, "orbit:6"});
  for (const Viewport vp : {Viewport{203, 117}, Viewport{256, 256}}) {
    for (const auto& [spec, path] : views) {
      SCOPED_TRACE(spec + " " + path + " " + std::to_string(vp.width) + "x" + std::to_string(vp.height));
      CpuAndGl g(spec, vp);
      std::optional<CpuOccluders>& cpu = g.cpu;
      SceneRenderer& renderer = *g.renderer;
      const Renderables& r = *g.r;
      const std::vector<uint32_t>& leaves = g.leaves;
      size_t nearer = 0, hidden = 0, hidden_but_shown = 0, tested = 0, covered = 0, lost = 0;
      for (const Camera& cam : load_camera_path(path, g.scene.bounds(), vp)) {
        // Occluders: most leaves, every third one left out (so that what is behind the holes shows).
        std::vector<uint32_t> occluders, others;
        for (size_t k = 0; k < leaves.size(); ++k) (k % 3 == 1 ? others : occluders).push_back(leaves[k]);
        renderer.begin_frame(cam, false);
        renderer.draw_renderables(r, occluders, SceneRenderer::Mode::DepthOnly);
        cpu->begin(cam);
        for (uint32_t id : occluders) cpu->draw_leaf(id, 0);
        const std::vector<float> gl_depth = g.ctx->read_depth();
        const std::span<const float> cpu_depth = cpu->raster().depth();
        for (size_t p = 0; p < gl_depth.size(); ++p) nearer += cpu_depth[p] > gl_depth[p];
        for (size_t p = 0; p < gl_depth.size(); ++p) {
          covered += gl_depth[p] > 0;
          lost += gl_depth[p] > 0 && cpu_depth[p] == 0;
        }
        for (uint32_t id : others) {
          ++tested;
          if (cpu->leaf_shows(id)) continue;
          ++hidden;
          hidden_but_shown += g.samples(id) > 0;
        }
      }
      EXPECT_EQ(nearer, 0u) << "pixels where the CPU's depth is nearer than GL's";
      EXPECT_EQ(hidden_but_shown, 0u) << "of " << hidden << " leaves found hidden, GL's query saw samples";
      // It must prove something, or the checks above say nothing; and it covers nearly what GL
      // covers: it leaves out only centres within rounding of an outline (a few percent where
      // thin parts are tessellated finer than a pixel, as the pipes' at low resolution).
      EXPECT_GT(hidden, 0u) << "of " << tested;
      EXPECT_LE(lost, covered / 20) << "of " << covered << " pixels GL covers, left uncovered";
    }
  }
}

// HC's box tests on the CPU (RasterQueries) against GL: a leaf whose box it finds occluded
// passes no sample of GL's occlusion query of the leaf's triangles over GL's depth of the
// occluders (the render client's frame); and it proves nearly what GL's query of the box
// (BoxQuerier, as HC in GL) proves over the same CPU depth uploaded.
TEST(CpuHc, BoxesItFindsOccludedHideTheirContentInGlAsGlsQueriesFind) {
  std::vector<std::pair<std::string, std::string>> views = {
      {"office", "walk:6"}, {"city:8x8:3:10:1", "walk:6"}, {"hard:cracks", "walk:6"}, {"pipes", "orbit:6"}};
  for (const char* rel : {"2CylinderEngine/2CylinderEngine.gltf", "bim/schependomlaan/schependomlaan.gltf"})
    if (std::string p = shared_scene(rel); !p.empty()) views.push_back({p, "orbit:6"});
  // And hard:span's cameras (HardCases.TinyPartsInAHugeHall): near 1e-4 to 1e-5, far 2e5 to 1e6.
  views.push_back({"hard:span", "pinned"});
  const Viewport vp{256, 256};
  for (const auto& [spec, path] : views) {
    SCOPED_TRACE(spec + " " + path);
    CpuAndGl g(spec, vp);
    auto look = [](glm::dvec3 eye, glm::dvec3 target, double fovy, double n, double f) {
      return Camera::look_at(eye, target, {0, 1, 0}, fovy, 1.0, n, f);
    };
    const std::vector<Camera> cameras =
        path != "pinned" ? load_camera_path(path, g.scene.bounds(), vp)
                         : std::vector<Camera>{look({-0.02, 1.002, 0.001}, {0, 1.002, 0.001}, 40, 1e-4, 2e5),
                                               look({-0.005, 1.0005, 0.0005}, {0.001, 1.0005, 0.0005}, 60, 1e-4, 2e5),
                                               look({-3, 2, -1}, {5, 1, 0}, 60, 1e-3, 2e5),
                                               look({-4e4, 1e4, -4e4}, {0, 0, 0}, 60, 1.0, 2e5),
                                               look({0.0005, 1.0005, 0.5}, {0.0005, 1.0005, -1}, 90, 1e-5, 1e6)};
    BoxQuerier boxes(*g.ctx);
    RasterQueries rq(*g.cpu);
    const Hierarchy& h = g.h;
    std::optional<CpuOccluders>& cpu = g.cpu;
    SceneRenderer& renderer = *g.renderer;
    const std::vector<uint32_t>& leaves = g.leaves;
    size_t tested = 0, hidden = 0, hidden_but_shown = 0, gl_hidden = 0, gl_only = 0, cpu_only = 0;
    for (const Camera& cam : cameras) {
      const Frustum fr = cam.frustum();
      // Tested: every third leaf in the frustum (HC tests no other), the rest occluders.
      std::vector<uint32_t> occluders, others;
      for (size_t k = 0; k < leaves.size(); ++k)
        if (k % 3 != 1)
          occluders.push_back(leaves[k]);
        else if (fr.classify(h.node(leaves[k]).box) != Containment::Outside)
          others.push_back(leaves[k]);
      cpu->begin(cam);
      for (uint32_t id : occluders) cpu->draw_leaf(id, 0);
      rq.begin(cam);
      std::vector<uint8_t> cpu_hidden;
      for (uint32_t id : others) {
        const Aabb& box = h.node(id).box;
        const bool near = visible_without_query(box, cam);
        cpu_hidden.push_back(!near && rq.result(rq.issue(box)) == 0);
        rq.end_batch();
      }
      // GL's box queries over the CPU's depth, uploaded.
      renderer.begin_frame(cam, false);
      g.ctx->write_depth(cpu->raster().depth().data());
      boxes.begin(cam);
      for (size_t k = 0; k < others.size(); ++k) {
        const Aabb& box = h.node(others[k]).box;
        if (visible_without_query(box, cam)) continue;
        ++tested;
        const bool gl_occluded = boxes.result(boxes.issue(box)) == 0;
        boxes.reset();
        gl_hidden += gl_occluded;
        gl_only += gl_occluded && !cpu_hidden[k];
        cpu_only += !gl_occluded && cpu_hidden[k];
      }
      // Every interior node's box in the frustum too (the hall around hard:span's camera: the
      // eye inside the padded box, outside the box itself), against GL's query of it.
      for (uint32_t id = 0; id < h.size(); ++id) {
        const Aabb& box = h.node(id).box;
        if (h.node(id).leaf() || fr.classify(box) == Containment::Outside || visible_without_query(box, cam)) continue;
        const bool cpu_occluded = rq.result(rq.issue(box)) == 0;
        rq.end_batch();
        const bool gl_occluded = boxes.result(boxes.issue(box)) == 0;
        boxes.reset();
        cpu_only += cpu_occluded && !gl_occluded;
      }
      boxes.end();
      // The leaves' own triangles over GL's depth of the occluders (no offset: the client's frame).
      renderer.begin_frame(cam, false);
      renderer.draw_renderables(*g.r, occluders, SceneRenderer::Mode::DepthOnly);
      for (size_t k = 0; k < others.size(); ++k) {
        if (!cpu_hidden[k]) continue;
        ++hidden;
        hidden_but_shown += g.samples(others[k]) > 0;
      }
    }
    std::printf("%s: %zu boxes, %zu occluded on the CPU, %zu by GL's queries (%zu of them not on the CPU, %zu only on it)\n",
                spec.c_str(), tested, hidden, gl_hidden, gl_only, cpu_only);
    EXPECT_EQ(hidden_but_shown, 0u) << "of " << hidden << " leaves whose boxes were found occluded, GL's query saw samples";
    EXPECT_GT(hidden, 0u) << "of " << tested;
    EXPECT_LE(gl_only, gl_hidden / 20) << "of " << gl_hidden << " boxes GL's queries find occluded, not found on the CPU";
    EXPECT_EQ(cpu_only, 0u) << "boxes found occluded on the CPU where GL's query of the box counts samples";
  }
}

// HC's central promise where the switch tests the boxes of V's own objects against V's depth: a
// leaf that shows in the frame (the item buffer of the whole scene) is never found occluded,
// nor any box above it, with every leaf drawn as an occluder, on the CPU (RasterQueries) and by
// GL's query over GL's OR (occluder offset on). hard:walls with the eye 0.0015-0.002 before wall 1
// (a zero-thickness box) and the near plane at 0.001 (HardCases.NearOneThousandthFarOneMillion):
// the pad put the padded box's front face before the near plane, its back face lay behind the
// wall itself, and both found the wall occluded until a padded box within reach of the near
// rectangle counted as visible. Also walks through walls and an office walk.
TEST(CpuHc, NoBoxOfWhatShowsIsFoundOccludedBehindItsOwnContent) {
  const Viewport vp{128, 96};
  const double aspect = double(vp.width) / double(vp.height);
  auto look = [&](glm::dvec3 eye, glm::dvec3 target, double fovy, double n, double f) {
    return Camera::look_at(eye, target, {0, 1, 0}, fovy, aspect, n, f);
  };
  struct View {
    std::string spec;
    std::vector<Camera> cameras;
  };
  std::vector<View> views = {{"hard:walls",
                              {look({9.998, 2, 3}, {20, 2, 3}, 60, 1e-3, 1e6), look({9.9985, 2, 3}, {20, 2, 3}, 60, 1e-3, 1e6),
                               look({14.499, 0.5, 0}, {0, 0.5, 0}, 60, 1e-3, 1e6),
                               look({9.99, 2, 3}, {19.99, 2, 3.1}, 60, 1e-3, 1e6),
                               look({9.9995, 2, 3}, {19.9995, 2, 3.1}, 60, 1e-3, 1e6),
                               look({9.96, 2, 3}, {19.96, 2, 3}, 60, 0.05, 1e4),
                               look({9.999, 2, 3}, {19.999, 2, 3}, 60, 0.05, 1e4)}}};
  {
    CpuAndGl probe("office", vp);
    views.push_back({"office", load_camera_path("walk:8", probe.scene.bounds(), vp)});
  }
  for (const View& view : views) {
    SCOPED_TRACE(view.spec);
    CpuAndGl g(view.spec, vp);
    const Hierarchy& h = g.h;
    SceneRenderer& renderer = *g.renderer;
    RasterQueries rq(*g.cpu);
    BoxQuerier boxes(*g.ctx);
    std::vector<uint32_t> all_items(h.items().size());
    for (uint32_t i = 0; i < all_items.size(); ++i) all_items[i] = i;
    std::vector<uint32_t> parent(h.size(), ~0u);
    for (uint32_t id = 0; id < h.size(); ++id)
      for (uint32_t c = 0; !h.node(id).leaf() && c < h.node(id).child_count; ++c) parent[h.node(id).first_child + c] = id;
    size_t tested = 0, cpu_wrong = 0, gl_wrong = 0;
    for (size_t k = 0; k < view.cameras.size(); ++k) {
      const Camera& cam = view.cameras[k];
      // What shows: the leaves of the items in the whole scene's item buffer.
      renderer.begin_id_frame(cam);
      renderer.draw_items(all_items, SceneRenderer::Mode::ItemIds);
      std::vector<uint8_t> shows_item(h.items().size(), 0);
      for (uint32_t id : ids_in_image(g.ctx->read_rgba()))
        if (id < shows_item.size()) shows_item[id] = 1;
      // Every box on the way up from a leaf that shows.
      std::vector<uint8_t> test(h.size(), 0);
      for (uint32_t leaf : g.leaves)
        for (uint32_t i = h.node(leaf).first_item; i < h.node(leaf).first_item + h.node(leaf).item_count; ++i)
          if (shows_item[i])
            for (uint32_t n = leaf; n != ~0u && !test[n]; n = parent[n]) test[n] = 1;
      // Every leaf drawn as an occluder: on the CPU, and in GL as the OR draws (occluder offset).
      g.cpu->begin(cam);
      for (uint32_t leaf : g.leaves) g.cpu->draw_leaf(leaf, 0);
      rq.begin(cam);
      renderer.set_occluder_offset(true);
      renderer.begin_frame(cam, false);
      renderer.draw_renderables(*g.r, g.leaves, SceneRenderer::Mode::DepthOnly);
      renderer.set_occluder_offset(false);
      boxes.begin(cam);
      for (uint32_t id = 0; id < h.size(); ++id) {
        if (!test[id] || visible_without_query(h.node(id).box, cam)) continue;
        ++tested;
        const bool cpu_occluded = rq.result(rq.issue(h.node(id).box)) == 0;
        rq.end_batch();
        const bool gl_occluded = boxes.result(boxes.issue(h.node(id).box)) == 0;
        boxes.reset();
        cpu_wrong += cpu_occluded;
        gl_wrong += gl_occluded;
        EXPECT_FALSE(cpu_occluded) << "camera " << k << ": node " << id << " found occluded on the CPU";
        EXPECT_FALSE(gl_occluded) << "camera " << k << ": node " << id << " found occluded by GL's query";
      }
      boxes.end();
    }
    std::printf("%s: %zu boxes of what shows tested, %zu found occluded on the CPU, %zu by GL's queries\n",
                view.spec.c_str(), tested, cpu_wrong, gl_wrong);
    EXPECT_GT(tested, 0u);
  }
}
