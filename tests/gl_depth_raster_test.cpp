// The OR on the CPU (common/cull/depth_raster.hpp) against llvmpipe's own depth of the same
// occluders: its depth is never nearer than GL's, it covers nearly all GL covers (walks through
// walls included: triangles across the near plane, corners far off screen), and a leaf it finds
// hidden by its own triangles passes no sample of GL's occlusion query of those triangles (what
// the render client's frame would show of it).
#include <gtest/gtest.h>

#include <filesystem>

#include "common/camera_path.hpp"
#include "common/cull/depth_raster.hpp"
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
}  // namespace

TEST(CpuOr, NeverNearerThanGlAndHidesOnlyWhatGlHides) {
  std::vector<std::pair<std::string, std::string>> views = {
      {"office", "walk:6"}, {"city:8x8:3:10:1", "walk:6"}, {"hard:cracks", "walk:6"}, {"plant:0.05", "walk:6"}, {"pipes", "orbit:6"}};
  for (const char* rel : {"2CylinderEngine/2CylinderEngine.gltf", "ReciprocatingSaw/ReciprocatingSaw.gltf"})
    if (std::string p = shared_scene(rel); !p.empty()) views.push_back({p, "orbit:6"});
  for (const Viewport vp : {Viewport{203, 117}, Viewport{256, 256}}) {
    for (const auto& [spec, path] : views) {
      SCOPED_TRACE(spec + " " + path + " " + std::to_string(vp.width) + "x" + std::to_string(vp.height));
      Scene scene = load_scene(spec);
      const Hierarchy h = Hierarchy::build(scene, {});
      std::string why;
      std::optional<CpuOccluders> cpu = CpuOccluders::copy(scene, h, vp.width, vp.height, &why);
      ASSERT_TRUE(cpu) << why;
      auto ctx = GlContext::create(GlBackend::Auto, vp.width, vp.height);
      SceneRenderer renderer(*ctx, scene, h);
      // No occluder offset: the depth of the render client's frame, what HC's answers must hold for
      // (the switch nodes' OR moves its occluders back further).
      const Renderables r(h, nullptr);
      const GlApi& gl = ctx->gl();
      GLuint query = 0;
      gl.CreateQueries(GL_SAMPLES_PASSED, 1, &query);
      std::vector<uint32_t> leaves;
      for (uint32_t id = 0; id < h.size(); ++id)
        if (h.node(id).leaf() && h.node(id).item_count > 0) leaves.push_back(id);
      size_t nearer = 0, hidden = 0, hidden_but_shown = 0, tested = 0, covered = 0, lost = 0;
      for (const Camera& cam : load_camera_path(path, scene.bounds(), vp)) {
        // Occluders: most leaves, every third one left out (so that what is behind the holes shows).
        std::vector<uint32_t> occluders, others;
        for (size_t k = 0; k < leaves.size(); ++k) (k % 3 == 1 ? others : occluders).push_back(leaves[k]);
        renderer.begin_frame(cam, false);
        renderer.draw_renderables(r, occluders, SceneRenderer::Mode::DepthOnly);
        cpu->begin(cam);
        for (uint32_t id : occluders) cpu->draw_leaf(id, 0);
        const std::vector<float> gl_depth = ctx->read_depth();
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
          const uint32_t ids[1] = {id};
          renderer.query_renderables(r, ids, query, GL_GREATER);
          GLuint64 samples = 0;
          gl.GetQueryObjectui64v(query, GL_QUERY_RESULT, &samples);
          hidden_but_shown += samples > 0;
        }
      }
      gl.DeleteQueries(1, &query);
      EXPECT_EQ(nearer, 0u) << "pixels where the CPU's depth is nearer than GL's";
      EXPECT_EQ(hidden_but_shown, 0u) << "of " << hidden << " leaves found hidden, GL's query saw samples";
      // It must prove something, or the checks above say nothing; and it covers nearly what GL
      // covers: it leaves out only centres within rounding of an outline (a few percent where
      // thin parts are tessellated finer than a pixel: the pipes at 203 x 117 lose 2.9 %).
      EXPECT_GT(hidden, 0u) << "of " << tested;
      EXPECT_LE(lost, covered / 20) << "of " << covered << " pixels GL covers, left uncovered";
    }
  }
}
