// glTF materials through load_gltf and SceneRenderer: one small .glb per material mode (written
// here) rendered from a camera on +Z looking down -Z (60 degrees, 128 x 128: at distance d the
// view spans +-0.577 d), pixels checked. Unlit materials (KHR_materials_unlit) give exact colours.
#include <gtest/gtest.h>

#include <cmath>
#include <numeric>

#include "common/cull/culling.hpp"
#include "common/gl/box_query.hpp"
#include "common/gl/context.hpp"
#include "common/gl/scene_renderer.hpp"
#include "common/scene/hierarchy.hpp"
#include "common/scene/scene_io.hpp"
#include "material_util.hpp"
#include "scratch_util.hpp"

using namespace occ;
using namespace mattest;

namespace {

constexpr int kSize = 128;
using Rgba = std::array<uint8_t, 4>;
constexpr Rgba kBackground = SceneRenderer::kBackgroundRgba8;

Camera camera_at(glm::dvec3 eye, glm::dvec3 target = {0, 0, 0}) {
  return Camera::look_at(eye, target, {0, 1, 0}, 60.0, 1.0, 0.1, 100.0);
}

Rgba pixel(const Image& img, int x, int y) {
  const uint8_t* p = &img.rgba[(size_t(y) * img.width + x) * 4];
  return {p[0], p[1], p[2], p[3]};
}

bool near(Rgba a, Rgba b, int tol = 1) {
  for (int c = 0; c < 4; ++c)
    if (std::abs(int(a[c]) - int(b[c])) > tol) return false;
  return true;
}

std::string str(Rgba c) {
  return "(" + std::to_string(c[0]) + "," + std::to_string(c[1]) + "," + std::to_string(c[2]) + "," +
         std::to_string(c[3]) + ")";
}

std::vector<uint32_t> all_items(const Hierarchy& h) {
  std::vector<uint32_t> v(h.items().size());
  std::iota(v.begin(), v.end(), 0u);
  return v;
}

// Writes .glb files into a per-test folder; loads and renders them.
class Materials : public occtest::ScratchDirTest {
 protected:
  void SetUp() override {
    ScratchDirTest::SetUp();
    ctx_ = GlContext::create(GlBackend::Auto, kSize, kSize);
  }

  GltfBuilder builder() const { return GltfBuilder(dir_); }
  Scene load(GltfBuilder& b, const std::string& name = "scene.glb") { return load_gltf(b.write_glb(dir_ / name)); }

  // Renders every item of `scene` (in the order given, or reversed) shaded from `cam`.
  Image render(Scene scene, const Camera& cam, bool reversed = false, std::string* variants = nullptr) {
    Hierarchy h = Hierarchy::build(scene, {});
    SceneRenderer r(*ctx_, scene, h);
    if (variants) *variants = r.variants();
    std::vector<uint32_t> items = all_items(h);
    if (reversed) std::reverse(items.begin(), items.end());
    r.begin_frame(cam, true);
    r.draw_items(items, SceneRenderer::Mode::Shaded);
    return ctx_->read_rgba();
  }

  std::unique_ptr<GlContext> ctx_;
};

const Camera kFront = camera_at({0, 0, 2});

}  // namespace

TEST_F(Materials, BaseColorFactorUnlitIsExactAndLitIsShadedByTheHeadlight) {
  GltfBuilder b = builder();
  b.node(b.quad(b.material(mat({1.0f, 0.5f, 0.0f, 1.0f}))), {-0.3, 0, 0}, glm::dvec3(0.5));
  b.node(b.quad(b.material(mat({0.0f, 0.0f, 1.0f, 1.0f}, "OPAQUE", false, false))), {0.3, 0, 0}, glm::dvec3(0.5));
  std::string variants;
  const Image img = render(load(b), kFront, false, &variants);
  EXPECT_TRUE(near(pixel(img, 40, 64), {255, 128, 0, 255})) << str(pixel(img, 40, 64));
  // Lit, facing the eye: 0.2 + 0.8 |n.l| with |n.l| close to 1 near the centre of the view.
  const Rgba lit = pixel(img, 88, 64);
  EXPECT_EQ(lit[0], 0);
  EXPECT_EQ(lit[1], 0);
  EXPECT_GT(lit[2], 240);
  EXPECT_EQ(pixel(img, 64, 10), kBackground);
  EXPECT_EQ(variants, "shaded: plain, unlit; depth: plain; ids: plain");
}

TEST_F(Materials, VertexColorsMultiplyTheBaseColor) {
  GltfBuilder b = builder();
  // Corners (-,-) red, (+,-) green, (+,+) blue, (-,+) white; base colour halves green.
  b.node(b.quad(b.material(mat({1.0f, 0.5f, 1.0f, 1.0f})), false,
                {1, 0, 0, 1, 0, 1, 0, 1, 0, 0, 1, 1, 1, 1, 1, 1}),
         {0, 0, 0});
  std::string variants;
  const Image img = render(load(b), kFront, false, &variants);
  // The quad spans pixels 64 +- 27; sample just inside each corner (y grows downwards).
  const Rgba bottom_left = pixel(img, 38, 90), bottom_right = pixel(img, 90, 90);
  const Rgba top_right = pixel(img, 90, 38), top_left = pixel(img, 38, 38);
  EXPECT_GT(bottom_left[0], 200) << str(bottom_left);
  EXPECT_LT(bottom_left[1], 30) << str(bottom_left);
  EXPECT_GT(bottom_right[1], 100) << str(bottom_right);  // green x 0.5
  EXPECT_LT(bottom_right[1], 135) << str(bottom_right);
  EXPECT_LT(bottom_right[0], 30) << str(bottom_right);
  EXPECT_GT(top_right[2], 200) << str(top_right);
  EXPECT_GT(top_left[0], 200) << str(top_left);
  EXPECT_GT(top_left[2], 200) << str(top_left);
  EXPECT_NE(variants.find("vertex-coloured"), std::string::npos) << variants;
}

TEST_F(Materials, TextureRoundTripsThroughAGlbWithItsSampler) {
  // 2 x 2 texels: top row red, green; bottom row blue, white. glTF uv (0, 0) is the image's
  // top-left texel and the quad's top-left corner carries uv (0, 0).
  Image tex = solid(2, 2, {255, 255, 255, 255});
  set_texel(tex, 0, 0, {255, 0, 0, 255});
  set_texel(tex, 1, 0, {0, 255, 0, 255});
  set_texel(tex, 0, 1, {0, 0, 255, 255});
  GltfBuilder b = builder();
  json m = mat({1, 1, 1, 1});
  m["pbrMetallicRoughness"]["baseColorTexture"] = {{"index", b.texture(tex, {{"magFilter", 9728}, {"minFilter", 9728}})}};
  b.node(b.quad(b.material(m), true), {0, 0, 0});
  const Scene scene = load(b);
  ASSERT_EQ(scene.images.size(), 1u);
  EXPECT_EQ(scene.images[0].rgba, tex.rgba) << "decoded as written";
  ASSERT_EQ(scene.textures.size(), 1u);
  EXPECT_EQ(scene.textures[0].sampler.mag_filter, 9728);
  std::string variants;
  const Image img = render(scene, kFront, false, &variants);
  // The quad spans pixels 64 +- 27.
  EXPECT_EQ(pixel(img, 50, 50), (Rgba{255, 0, 0, 255}));     // top-left of the quad
  EXPECT_EQ(pixel(img, 78, 50), (Rgba{0, 255, 0, 255}));     // top-right
  EXPECT_EQ(pixel(img, 50, 78), (Rgba{0, 0, 255, 255}));     // bottom-left
  EXPECT_EQ(pixel(img, 78, 78), (Rgba{255, 255, 255, 255}));  // bottom-right
  EXPECT_EQ(pixel(img, 30, 64), kBackground);
  EXPECT_EQ(variants, "shaded: textured+unlit; depth: plain; ids: plain");
}

TEST_F(Materials, SingleSidedFacesAreCulledFromBehindAndMirroredObjectsKeepTheirFront) {
  GltfBuilder b = builder();
  const int single = b.quad(b.material(mat({1, 0, 0, 1})));
  const int both = b.quad(b.material(mat({0, 1, 0, 1}, "OPAQUE", true)));
  // Row y = +0.3: facing the eye; row y = -0.3: turned away (180 degrees about y).
  b.node(single, {-0.3, 0.3, 0}, glm::dvec3(0.4));
  b.node(single, {-0.3, -0.3, 0}, glm::dvec3(0.4), about_y(180));
  b.node(both, {0.3, -0.3, 0}, glm::dvec3(0.4), about_y(180));
  // Mirrored in x (negative determinant): its triangles wind clockwise on screen, yet glTF makes
  // clockwise the front: still visible from +Z.
  b.node(single, {0.3, 0.3, 0}, {-0.4, 0.4, 0.4});
  const Image img = render(load(b), kFront);
  EXPECT_EQ(pixel(img, 47, 47), (Rgba{255, 0, 0, 255})) << "single-sided, facing the eye";
  EXPECT_EQ(pixel(img, 47, 81), kBackground) << "single-sided, seen from behind: culled";
  EXPECT_EQ(pixel(img, 81, 81), (Rgba{0, 255, 0, 255})) << "double-sided, seen from behind";
  EXPECT_EQ(pixel(img, 81, 47), (Rgba{255, 0, 0, 255})) << "mirrored, facing the eye";
  // From behind, the mirrored quad is culled too.
  const Image back = render(load(b), camera_at({0, 0, -2}));
  EXPECT_EQ(pixel(back, 47, 47), kBackground) << "mirrored quad from behind (left on screen from -Z)";
  EXPECT_EQ(pixel(back, 81, 47), kBackground) << "single-sided quad from behind";
}

TEST_F(Materials, MaskDiscardsBelowTheCutoffInEveryPass) {
  // A textured MASK quad in front: left half of the texture alpha 0, right half alpha 1; behind
  // it an opaque red quad. A uniform alpha of 0.4 (cutoff 0.5) hides a second masked quad.
  Image tex = solid(2, 1, {255, 255, 255, 255});
  set_texel(tex, 0, 0, {255, 255, 255, 0});
  GltfBuilder b = builder();
  json m = mat({0, 0, 1, 1}, "MASK");
  m["alphaCutoff"] = 0.5;
  m["pbrMetallicRoughness"]["baseColorTexture"] = {{"index", b.texture(tex, {{"magFilter", 9728}, {"minFilter", 9728}})}};
  b.node(b.quad(b.material(m), true), {0, 0.25, 0.5}, {1.0, 0.4, 1.0});
  json faint = mat({0, 1, 0, 0.4f}, "MASK");
  b.node(b.quad(b.material(faint)), {0, -0.25, 0.5}, {1.0, 0.4, 1.0});
  b.node(b.quad(b.material(mat({1, 0, 0, 1}))), {0, 0, 0}, glm::dvec3(1.2));
  Scene scene = load(b);
  Hierarchy h = Hierarchy::build(scene, {});
  SceneRenderer r(*ctx_, scene, h);
  EXPECT_EQ(r.variants(), "shaded: unlit, masked+unlit, textured+masked+unlit; depth: plain, masked, textured+masked; "
                          "ids: plain, masked, textured+masked");
  r.begin_frame(kFront, true);
  r.draw_items(all_items(h), SceneRenderer::Mode::Shaded);
  Image img = ctx_->read_rgba();
  EXPECT_EQ(pixel(img, 40, 40), (Rgba{255, 0, 0, 255})) << "through the alpha-0 half";
  EXPECT_EQ(pixel(img, 88, 40), (Rgba{0, 0, 255, 255})) << "the alpha-1 half";
  EXPECT_EQ(pixel(img, 64, 88), (Rgba{255, 0, 0, 255})) << "alpha 0.4 < cutoff 0.5: nothing of it";
  // Depth-only: the masked quads write depth only where the test passes. Boxes just behind each
  // half of the masked quads (in front of the red quad) show samples only behind the holes.
  r.begin_frame(kFront, true);
  r.draw_items(all_items(h), SceneRenderer::Mode::DepthOnly);
  BoxQuerier q(*ctx_);
  q.begin(kFront);
  const uint32_t behind_hole = q.issue(Aabb{{-0.4, 0.15, 0.2}, {-0.1, 0.35, 0.3}});
  const uint32_t behind_solid = q.issue(Aabb{{0.1, 0.15, 0.2}, {0.4, 0.35, 0.3}});
  const uint32_t behind_faint = q.issue(Aabb{{-0.2, -0.35, 0.2}, {0.2, -0.15, 0.3}});
  EXPECT_GT(q.result(behind_hole), 0u);
  EXPECT_EQ(q.result(behind_solid), 0u);
  EXPECT_GT(q.result(behind_faint), 0u);
  q.end();
  // The item buffer: the red quad is seen through the holes, the faint quad nowhere.
  r.begin_id_frame(kFront);
  r.draw_items(all_items(h), SceneRenderer::Mode::ItemIds);
  std::vector<uint32_t> objects;
  for (uint32_t item : ids_in_image(ctx_->read_rgba())) objects.push_back(h.items()[item].object);
  std::sort(objects.begin(), objects.end());
  EXPECT_EQ(objects, (std::vector<uint32_t>{0, 2}));
}

TEST_F(Materials, BlendIsDrawnAfterOpaqueBackToFrontAndNeverOccludes) {
  // Two glass panes (blue alpha 0.5 nearer, green alpha 0.5 farther) in front of a red quad.
  GltfBuilder b = builder();
  b.node(b.quad(b.material(mat({0, 0, 1, 0.5f}, "BLEND"))), {0, 0, 0.6}, glm::dvec3(0.6));
  b.node(b.quad(b.material(mat({0, 1, 0, 0.5f}, "BLEND"))), {0, 0, 0.3}, glm::dvec3(0.6));
  b.node(b.quad(b.material(mat({1, 0, 0, 1}))), {0, 0, 0}, glm::dvec3(1.2));
  Scene scene = load(b);
  // Over red: green at 0.5, then blue at 0.5: (0.25, 0.25, 0.5) of 255.
  const Rgba expected{64, 64, 128, 255};
  std::string variants;
  for (bool reversed : {false, true}) {
    const Image img = render(scene, kFront, reversed, &variants);
    EXPECT_TRUE(near(pixel(img, 64, 64), expected)) << str(pixel(img, 64, 64)) << (reversed ? " reversed" : "");
    EXPECT_EQ(pixel(img, 36, 64), (Rgba{255, 0, 0, 255}));
  }
  EXPECT_EQ(variants, "shaded: unlit, blended+unlit; depth: plain; ids: plain");

  Hierarchy h = Hierarchy::build(scene, {});
  SceneRenderer r(*ctx_, scene, h);
  EXPECT_TRUE(r.has_blended());
  // Deferred: a renderer that draws a leaf at a time gets the glass at end_frame().
  r.begin_frame(kFront, true, true);
  std::vector<uint32_t> items = all_items(h);
  DrawStats drawn;
  for (uint32_t item : items) drawn += r.draw_items({&item, 1}, SceneRenderer::Mode::Shaded);
  EXPECT_EQ(drawn.items, 1u) << "only the opaque quad so far";
  EXPECT_EQ(r.end_frame().items, 2u);
  EXPECT_TRUE(near(pixel(ctx_->read_rgba(), 64, 64), expected));
  // Depth-only: no glass; a box between the glass and the red quad has samples.
  r.begin_frame(kFront, true);
  EXPECT_EQ(r.draw_items(items, SceneRenderer::Mode::DepthOnly).items, 1u);
  BoxQuerier q(*ctx_);
  q.begin(kFront);
  EXPECT_GT(q.result(q.issue(Aabb{{-0.1, -0.1, 0.1}, {0.1, 0.1, 0.2}})), 0u) << "glass must not occlude";
  q.end();
  // The item buffer holds what is seen through the glass, not the glass.
  r.begin_id_frame(kFront);
  r.draw_items(items, SceneRenderer::Mode::ItemIds);
  std::vector<uint32_t> objects;
  for (uint32_t item : ids_in_image(ctx_->read_rgba())) objects.push_back(h.items()[item].object);
  EXPECT_EQ(objects, (std::vector<uint32_t>{2}));
}

TEST_F(Materials, PrimitivesWithoutMaterialAndGeneratedScenesKeepTheHashedColours) {
  GltfBuilder b = builder();
  b.node(b.quad(-1), {0, 0, 0});
  Scene scene = load(b);
  ASSERT_EQ(scene.materials.size(), 1u);
  EXPECT_TRUE(scene.materials[0].object_color);
  EXPECT_FALSE(scene.materials[0].double_sided) << "the glTF default material is single-sided";
  const Rgba c = pixel(render(scene, kFront), 64, 64);
  EXPECT_NE(c, kBackground);
  EXPECT_GT(std::min({c[0], c[1], c[2]}), 90) << "a pastel, lit: " << str(c);
  EXPECT_EQ(pixel(render(scene, camera_at({0, 0, -2})), 64, 64), kBackground) << "culled from behind";
  // Generated geometry (no material at all) is double-sided.
  Scene gen;
  gen.meshes.push_back(scene.meshes[0]);
  gen.meshes[0].material = kNoMaterial;
  gen.objects.push_back(scene.objects[0]);
  EXPECT_EQ(pixel(render(gen, kFront), 64, 64), c) << "the same hashed colour";
  EXPECT_NE(pixel(render(gen, camera_at({0, 0, -2})), 64, 64), kBackground);
}
