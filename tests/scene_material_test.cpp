// glTF materials in the scene model (no GL): what load_gltf reads (factors, alpha modes,
// double-sidedness, unlit, textures with samplers and TEXCOORD_n, COLOR_0), what it decodes (only
// images a drawn material uses), and one clear error naming the element for bad material input.
#include <gtest/gtest.h>

#include "common/error.hpp"
#include "common/scene/scene_io.hpp"
#include "material_util.hpp"
#include "scratch_util.hpp"

using namespace occ;
using namespace mattest;

namespace {

class MaterialFiles : public occtest::ScratchDirTest {
 protected:
  GltfBuilder builder() const { return GltfBuilder(dir_); }
  std::string write(GltfBuilder& b, const std::string& name = "m.glb") const { return b.write_glb(dir_ / name); }

  // load_gltf throws InputError naming the file and every word.
  void expect_error(GltfBuilder& b, std::initializer_list<const char*> words) const {
    const std::string path = write(b);
    try {
      load_gltf(path);
      ADD_FAILURE() << "loaded, expected an error";
    } catch (const InputError& e) {
      const std::string msg = e.what();
      EXPECT_NE(msg.find("m.glb"), std::string::npos) << msg;
      for (const char* w : words) EXPECT_NE(msg.find(w), std::string::npos) << "'" << w << "' not in: " << msg;
    }
  }
};

}  // namespace

TEST_F(MaterialFiles, FactorsModesSidednessAndUnlitAreRead) {
  GltfBuilder b = builder();
  json glass = mat({0.1f, 0.2f, 0.3f, 0.4f}, "BLEND", true, false);
  glass["name"] = "glass";
  json leaves = mat({1, 1, 1, 1}, "MASK", false, true);
  leaves["alphaCutoff"] = 0.25;
  const int g = b.material(glass), l = b.material(leaves);
  const int qg = b.quad(g);
  b.node(qg, {0, 0, 0});
  b.node(qg, {2, 0, 0});           // the same mesh twice: one material
  b.node(b.quad(l), {4, 0, 0});
  b.node(b.quad(-1), {6, 0, 0});   // no material: the glTF default
  b.node(b.box(g), {8, 0, 0});     // another mesh with the same material
  const Scene s = load_gltf(write(b));
  ASSERT_EQ(s.materials.size(), 3u);
  const Material& m0 = s.materials[s.meshes[s.objects[0].mesh].material];
  EXPECT_EQ(m0.name, "glass");
  EXPECT_EQ(m0.base_color, glm::vec4(0.1f, 0.2f, 0.3f, 0.4f));
  EXPECT_EQ(m0.alpha_mode, AlphaMode::Blend);
  EXPECT_TRUE(m0.double_sided);
  EXPECT_FALSE(m0.unlit);
  EXPECT_EQ(m0.base_color_texture, -1);
  EXPECT_EQ(s.meshes[s.objects[4].mesh].material, s.meshes[s.objects[0].mesh].material);
  const Material& m2 = s.materials[s.meshes[s.objects[2].mesh].material];
  EXPECT_EQ(m2.alpha_mode, AlphaMode::Mask);
  EXPECT_FLOAT_EQ(m2.alpha_cutoff, 0.25f);
  EXPECT_TRUE(m2.unlit);
  EXPECT_FALSE(m2.double_sided);
  const Material* def = s.material_of(s.objects[3].mesh);
  ASSERT_NE(def, nullptr);
  EXPECT_TRUE(def->object_color);
  EXPECT_FALSE(def->double_sided);
  EXPECT_EQ(def->alpha_mode, AlphaMode::Opaque);
  EXPECT_TRUE(s.images.empty());
}

TEST_F(MaterialFiles, VertexColorsAndTheTexturesCoordinateSetAreRead) {
  GltfBuilder b = builder();
  Image tex = solid(4, 2, {10, 20, 30, 40});
  json m = mat({1, 1, 1, 1});
  m["pbrMetallicRoughness"]["baseColorTexture"] = {{"index", b.texture(tex, {{"wrapS", 33071}, {"wrapT", 33648}})},
                                                   {"texCoord", 1}};
  const int q = b.quad(b.material(m), true, {2.0f, 0.5f, -1.0f, 1.0f, 0, 0, 0, 0, 1, 1, 1, 0.5f, 0, 1, 0, 1});
  // TEXCOORD_1: normalized unsigned shorts; COLOR_0 above: float VEC4 (2 and -1 are clamped).
  auto& prim = b.j["meshes"][q]["primitives"][0];
  prim["attributes"]["TEXCOORD_1"] =
      b.accessor(std::vector<uint16_t>{0, 65535, 65535, 65535, 65535, 0, 0, 0}, 5123, 4, "VEC2", true);
  b.node(q, {0, 0, 0});
  const Scene s = load_gltf(write(b));
  const Mesh& mesh = s.meshes[0];
  ASSERT_EQ(mesh.colors.size(), 4u);
  EXPECT_EQ(mesh.colors[0], 0xff0080ffu);  // (1, 0.5, 0, 1) as RGBA8, r in the low byte
  EXPECT_EQ(mesh.colors[2], 0x80ffffffu);
  ASSERT_EQ(mesh.uvs.size(), 4u);
  EXPECT_EQ(mesh.uvs[0], glm::vec2(0, 1));
  EXPECT_EQ(mesh.uvs[2], glm::vec2(1, 0));
  ASSERT_EQ(s.textures.size(), 1u);
  EXPECT_EQ(s.textures[0].sampler.wrap_s, 33071);
  EXPECT_EQ(s.textures[0].sampler.wrap_t, 33648);
  EXPECT_EQ(s.textures[0].sampler.min_filter, -1);
  ASSERT_EQ(s.images.size(), 1u);
  EXPECT_EQ(s.images[0].width, 4);
  EXPECT_EQ(s.images[0].height, 2);
  EXPECT_EQ(s.images[0].rgba, tex.rgba);

  // A layout copies materials, textures and images; the content hash covers materials.
  const std::string path = write(b, "asset.glb");
  const Scene grid = load_scene("layout:2x1:" + path);
  EXPECT_EQ(grid.materials.size(), s.materials.size());
  EXPECT_EQ(grid.images.size(), 1u);
  GltfBuilder b2 = b;
  b2.j["materials"][0]["alphaMode"] = "BLEND";
  EXPECT_NE(load_gltf(write(b2, "blend.glb")).content_hash(), s.content_hash());
  EXPECT_EQ(load_gltf(write(b, "again.glb")).content_hash(), s.content_hash());
}

TEST_F(MaterialFiles, OnlyImagesOfDrawnMaterialsAreDecoded) {
  GltfBuilder b = builder();
  json m = mat({1, 1, 1, 1});
  m["pbrMetallicRoughness"]["baseColorTexture"] = {{"index", b.texture(solid(2, 2, {1, 2, 3, 4}))}};
  b.material(m);  // material 0: used by no primitive
  const int garbage = b.view("not an image", 12);
  b.j["images"].push_back({{"bufferView", garbage}, {"mimeType", "image/png"}});  // never referenced
  b.node(b.quad(-1), {0, 0, 0});
  const Scene s = load_gltf(write(b));
  EXPECT_TRUE(s.images.empty());
  EXPECT_TRUE(s.textures.empty());
}

TEST_F(MaterialFiles, ZeroLengthNormalsAreRecomputed) {
  GltfBuilder b = builder();
  const int q = b.quad(-1);
  b.j["meshes"][q]["primitives"][0]["attributes"]["NORMAL"] =
      b.accessor(std::vector<float>{0, 0, 0, 0, 0, 1, 0, 0, 0, 0, 0, 1}, 5126, 4, "VEC3");
  b.node(q, {0, 0, 0});
  const Scene s = load_gltf(write(b));
  for (const glm::vec3& n : s.meshes[0].normals) EXPECT_NEAR(n.z, 1.0f, 1e-6f);
}

TEST_F(MaterialFiles, BadMaterialInputIsOneErrorNamingTheElement) {
  {
    GltfBuilder b = builder();
    json m = mat({1, 1, 1, 1});
    m["alphaMode"] = "GLASS";
    b.node(b.quad(b.material(m)), {0, 0, 0});
    expect_error(b, {"material 0", "alphaMode 'GLASS'"});
  }
  {
    GltfBuilder b = builder();
    b.node(b.quad(b.material(mat({1.5f, 1, 1, 1}))), {0, 0, 0});
    expect_error(b, {"material 0", "baseColorFactor"});
  }
  {
    GltfBuilder b = builder();
    b.node(b.quad(7), {0, 0, 0});
    expect_error(b, {"mesh 0 primitive 0", "material 7 out of range"});
  }
  {
    GltfBuilder b = builder();
    json m = mat({1, 1, 1, 1});
    m["pbrMetallicRoughness"]["baseColorTexture"] = {{"index", 3}};
    b.node(b.quad(b.material(m), true), {0, 0, 0});
    expect_error(b, {"material 0 baseColorTexture", "texture 3 out of range"});
  }
  {
    GltfBuilder b = builder();
    json m = mat({1, 1, 1, 1});
    m["pbrMetallicRoughness"]["baseColorTexture"] = {{"index", b.texture(solid(1, 1, {0, 0, 0, 255}))}};
    b.node(b.quad(b.material(m), false), {0, 0, 0});
    expect_error(b, {"mesh 0 primitive 0", "no TEXCOORD_0"});
  }
  {
    GltfBuilder b = builder();
    json m = mat({1, 1, 1, 1});
    m["pbrMetallicRoughness"]["baseColorTexture"] = {{"index", b.texture(solid(1, 1, {0, 0, 0, 255}), {{"wrapS", 1234}})}};
    b.node(b.quad(b.material(m), true), {0, 0, 0});
    expect_error(b, {"sampler 0", "wrapS 1234"});
  }
  {
    GltfBuilder b = builder();
    json m = mat({1, 1, 1, 1});
    m["pbrMetallicRoughness"]["baseColorTexture"] = {{"index", b.texture(solid(1, 1, {0, 0, 0, 255}))}};
    b.j["images"][0] = {{"bufferView", b.view("garbage bytes", 13)}, {"mimeType", "image/png"}};
    b.node(b.quad(b.material(m), true), {0, 0, 0});
    expect_error(b, {"image 0", "cannot decode"});
  }
  {
    GltfBuilder b = builder();
    json m = mat({1, 1, 1, 1});
    m["pbrMetallicRoughness"]["baseColorTexture"] = {{"index", b.texture(solid(1, 1, {0, 0, 0, 255}))}};
    b.j["images"][0] = {{"uri", "missing.png"}};
    b.node(b.quad(b.material(m), true), {0, 0, 0});
    expect_error(b, {"image 0", "missing.png"});
  }
  {
    GltfBuilder b = builder();
    json m = mat({1, 1, 1, 1});
    m["pbrMetallicRoughness"]["baseColorTexture"] = {{"index", b.texture(solid(1, 1, {0, 0, 0, 255}))}};
    b.j["textures"][0].erase("source");
    b.node(b.quad(b.material(m), true), {0, 0, 0});
    expect_error(b, {"texture 0", "no source image"});
  }
}
