// Assimp's scene (assimp_reader.hpp) turned into ours: nodes to objects, meshes and materials
// checked and converted once each.
#include "common/scene/assimp_reader.hpp"

#include <assimp/DefaultIOSystem.h>
#include <assimp/Importer.hpp>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <stb/stb_image.h>

#include <algorithm>
#include <climits>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <map>
#include <memory>

#include "common/error.hpp"
#include "common/scene/model_mesh.hpp"

namespace occ {
namespace {

// Assimp's file system, recording each file it opens (as it was just before) for Scene::files.
class RecordingIo : public Assimp::DefaultIOSystem {
 public:
  explicit RecordingIo(std::vector<SourceFile>* files) : files_(files) {}
  Assimp::IOStream* Open(const char* file, const char* mode) override {
    Assimp::IOStream* s = DefaultIOSystem::Open(file, mode);
    if (s) {
      const auto sf = source_file(file);
      if (sf && std::find(files_->begin(), files_->end(), *sf) == files_->end()) files_->push_back(*sf);
    }
    return s;
  }

 private:
  std::vector<SourceFile>* files_;
};

glm::dmat4 to_glm(const aiMatrix4x4& a) {
  glm::dmat4 m;
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) m[c][r] = double(a[r][c]);
  return m;
}

bool finite(const glm::dmat4& m) {
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 4; ++r)
      if (!std::isfinite(m[c][r])) return false;
  return true;
}

int32_t wrap_of(aiTextureMapMode m) {
  return m == aiTextureMapMode_Clamp || m == aiTextureMapMode_Decal ? 33071 : m == aiTextureMapMode_Mirror ? 33648 : 10497;
}

class AssimpReader {
 public:
  AssimpReader(const aiScene& sc, std::string file) : sc_(sc), file_(std::move(file)) {}

  Scene read() {
    std::vector<std::pair<const aiNode*, glm::dmat4>> stack{{sc_.mRootNode, glm::dmat4(1.0)}};
    while (!stack.empty()) {  // depth-first, children in file order
      auto [node, parent] = stack.back();
      stack.pop_back();
      const glm::dmat4 world = parent * to_glm(node->mTransformation);
      const std::string name = node->mName.length ? node->mName.C_Str() : "node " + std::to_string(nodes_);
      if (!finite(world)) fail("node '" + name + "'", "transform is not finite");
      ++nodes_;
      for (unsigned k = 0; k < node->mNumMeshes; ++k) {
        const unsigned mi = node->mMeshes[k];
        if (mi >= sc_.mNumMeshes) fail("node '" + name + "'", "mesh " + std::to_string(mi) + " out of range");
        const Built& b = mesh(mi);
        scene_.zero_area_triangles += b.zero_area;
        scene_.repeated_triangles += b.repeated;
        for (uint32_t m : b.meshes) scene_.objects.push_back(Object{m, world, name});
      }
      for (unsigned c = node->mNumChildren; c-- > 0;) stack.emplace_back(node->mChildren[c], world);
    }
    if (skipped_ > 0) std::cerr << file_ << ": skipped " << skipped_ << " meshes of points or lines\n";
    if (scene_.objects.empty()) throw InputError(file_ + ": no triangles to draw");
    return std::move(scene_);
  }

 private:
  [[noreturn]] void fail(const std::string& where, const std::string& what) const {
    throw InputError(file_ + ": " + where + ": " + what);
  }

  struct Built {
    std::vector<uint32_t> meshes;
    uint64_t zero_area = 0, repeated = 0;
  };

  const Built& mesh(unsigned mi) {
    auto [it, fresh] = built_.try_emplace(mi);
    if (fresh) it->second = build(mi);
    return it->second;
  }

  Built build(unsigned mi) {
    const aiMesh& am = *sc_.mMeshes[mi];
    const std::string where = "mesh " + std::to_string(mi) + (am.mName.length ? " '" + std::string(am.mName.C_Str()) + "'" : "");
    if (!(am.mPrimitiveTypes & (aiPrimitiveType_TRIANGLE | aiPrimitiveType_POLYGON))) {
      ++skipped_;
      return {};
    }
    Mesh m;
    m.name = am.mName.length ? am.mName.C_Str() : where;
    const unsigned nv = am.mNumVertices;
    m.positions.resize(nv);
    for (unsigned v = 0; v < nv; ++v) {
      m.positions[v] = {am.mVertices[v].x, am.mVertices[v].y, am.mVertices[v].z};
      if (!std::isfinite(m.positions[v].x) || !std::isfinite(m.positions[v].y) || !std::isfinite(m.positions[v].z))
        fail(where, "vertex " + std::to_string(v) + " is not finite");
    }
    m.indices.reserve(size_t(am.mNumFaces) * 3);
    for (unsigned f = 0; f < am.mNumFaces; ++f) {
      const aiFace& face = am.mFaces[f];
      if (face.mNumIndices != 3) continue;  // points and lines sorted into this mesh (SortByPType keeps none)
      for (unsigned k = 0; k < 3; ++k) {
        if (face.mIndices[k] >= nv) fail(where, "face " + std::to_string(f) + ": index out of range");
        m.indices.push_back(face.mIndices[k]);
      }
    }
    if (am.HasNormals()) {
      m.normals.resize(nv);
      for (unsigned v = 0; v < nv; ++v) {
        m.normals[v] = {am.mNormals[v].x, am.mNormals[v].y, am.mNormals[v].z};
        if (!std::isfinite(m.normals[v].x) || !std::isfinite(m.normals[v].y) || !std::isfinite(m.normals[v].z))
          m.normals[v] = glm::vec3(0.0f);  // repaired by add_model_mesh
      }
    }
    if (am.HasVertexColors(0)) {
      m.colors.resize(nv);
      for (unsigned v = 0; v < nv; ++v) {
        const aiColor4D& c = am.mColors[0][v];
        const float ch[4] = {c.r, c.g, c.b, c.a};
        uint32_t rgba = 0;
        for (int k = 0; k < 4; ++k)
          rgba |= uint32_t(std::lround(std::clamp(std::isfinite(ch[k]) ? ch[k] : 0.0f, 0.0f, 1.0f) * 255.0f)) << (8 * k);
        m.colors[v] = rgba;
      }
    }
    m.material = material(am.mMaterialIndex, !m.colors.empty(), where);
    if (m.material != kNoMaterial && scene_.materials[m.material].base_color_texture >= 0) {
      const unsigned ch = uv_channel_[m.material];
      if (ch >= AI_MAX_NUMBER_OF_TEXTURECOORDS || !am.HasTextureCoords(ch))
        fail(where, "its material has a texture but the mesh has no texture coordinates (set " + std::to_string(ch) + ")");
      m.uvs.resize(nv);
      for (unsigned v = 0; v < nv; ++v) {
        m.uvs[v] = {am.mTextureCoords[ch][v].x, am.mTextureCoords[ch][v].y};
        if (!std::isfinite(m.uvs[v].x) || !std::isfinite(m.uvs[v].y)) fail(where, "texture coordinate not finite");
      }
    }
    const ModelMeshCounts c = add_model_mesh(scene_, std::move(m), am.HasNormals());
    return {c.meshes, c.zero_area, c.repeated};
  }

  uint32_t material(unsigned index, bool vertex_colours, const std::string& where) {
    if (index >= sc_.mNumMaterials) fail(where, "material " + std::to_string(index) + " out of range");
    const aiMaterial& am = *sc_.mMaterials[index];
    aiString name;
    am.Get(AI_MATKEY_NAME, name);
    if (std::string(name.C_Str()) == AI_DEFAULT_MATERIAL_NAME)  // the file has no material for it
      return vertex_colours ? vertex_colour_material(scene_) : kNoMaterial;
    if (const auto it = materials_.find(index); it != materials_.end()) return it->second;
    Material m;
    const std::string mw = "material " + std::to_string(index);
    m.name = name.length ? name.C_Str() : mw;
    aiColor4D c(1, 1, 1, 1);
    if (am.Get(AI_MATKEY_BASE_COLOR, c) != AI_SUCCESS) am.Get(AI_MATKEY_COLOR_DIFFUSE, c);
    float opacity = 1.0f;
    am.Get(AI_MATKEY_OPACITY, opacity);
    m.base_color = {c.r, c.g, c.b, c.a * opacity};
    for (int k = 0; k < 4; ++k)
      if (!(m.base_color[k] >= 0.0f && m.base_color[k] <= 1.0f))
        fail(mw, "base colour (or diffuse colour and opacity) must be 4 numbers in [0, 1]");
    if (m.base_color.a < 1.0f) m.alpha_mode = AlphaMode::Blend;
    int two_sided = 0;
    m.double_sided = am.Get(AI_MATKEY_TWOSIDED, two_sided) == AI_SUCCESS && two_sided != 0;
    int shading = 0;
    m.unlit = am.Get(AI_MATKEY_SHADING_MODEL, shading) == AI_SUCCESS &&
              (shading == aiShadingMode_NoShading || shading == aiShadingMode_Unlit);
    unsigned channel = 0;
    for (aiTextureType t : {aiTextureType_BASE_COLOR, aiTextureType_DIFFUSE}) {
      aiString tex;
      aiTextureMapMode mode[2] = {aiTextureMapMode_Wrap, aiTextureMapMode_Wrap};
      unsigned uv = 0;
      if (am.GetTexture(t, 0, &tex, nullptr, &uv, nullptr, nullptr, mode) != AI_SUCCESS) continue;
      Texture texture;
      texture.image = image(tex.C_Str(), mw);
      texture.sampler.wrap_s = wrap_of(mode[0]);
      texture.sampler.wrap_t = wrap_of(mode[1]);
      scene_.textures.push_back(texture);
      m.base_color_texture = int32_t(scene_.textures.size() - 1);
      channel = uv;
      break;
    }
    scene_.materials.push_back(std::move(m));
    uv_channel_[uint32_t(scene_.materials.size() - 1)] = channel;
    return materials_[index] = uint32_t(scene_.materials.size() - 1);
  }

  // A texture's image: embedded ("*N" or a name the scene holds), else a file beside the model.
  uint32_t image(const std::string& ref, const std::string& mw) {
    if (const auto it = images_.find(ref); it != images_.end()) return it->second;
    int w = 0, h = 0, channels = 0;
    stbi_uc* px = nullptr;
    Image img;
    if (const aiTexture* t = sc_.GetEmbeddedTexture(ref.c_str())) {
      if (t->mHeight == 0) {
        if (t->mWidth > unsigned(INT_MAX)) fail(mw, "embedded texture larger than 2 GiB");
        px = stbi_load_from_memory(reinterpret_cast<const stbi_uc*>(t->pcData), int(t->mWidth), &w, &h, &channels, 4);
      } else {  // raw BGRA texels
        img.width = int(t->mWidth);
        img.height = int(t->mHeight);
        img.rgba.resize(size_t(t->mWidth) * t->mHeight * 4);
        for (size_t i = 0; i < size_t(t->mWidth) * t->mHeight; ++i) {
          const aiTexel& x = t->pcData[i];
          const uint8_t rgba[4] = {x.r, x.g, x.b, x.a};
          std::copy(rgba, rgba + 4, img.rgba.begin() + std::ptrdiff_t(4 * i));
        }
      }
    } else {
      std::string rel = ref;
      std::replace(rel.begin(), rel.end(), '\\', '/');
      const std::filesystem::path p = std::filesystem::path(file_).parent_path() / rel;
      if (auto sf = source_file(p.string())) scene_.files.push_back(*sf);
      px = stbi_load(p.string().c_str(), &w, &h, &channels, 4);
      if (!px) fail(mw, "cannot load texture '" + p.string() + "': " + stbi_failure_reason());
    }
    if (px) {
      img.width = w;
      img.height = h;
      img.rgba.assign(px, px + size_t(w) * size_t(h) * 4);
      stbi_image_free(px);
    } else if (img.rgba.empty()) {
      fail(mw, "cannot decode embedded texture '" + ref + "': " + stbi_failure_reason());
    }
    scene_.images.push_back(std::move(img));
    return images_[ref] = uint32_t(scene_.images.size() - 1);
  }

  const aiScene& sc_;
  std::string file_;
  Scene scene_;
  std::map<unsigned, Built> built_;            // Assimp mesh -> ours
  std::map<unsigned, uint32_t> materials_;     // Assimp material -> ours
  std::map<uint32_t, unsigned> uv_channel_;    // our material -> its texture's coordinate set
  std::map<std::string, uint32_t> images_;     // texture reference -> Scene::images
  size_t nodes_ = 0;
  int skipped_ = 0;
};

}  // namespace

Scene load_with_assimp(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) throw InputError(path + ": cannot open file: no such file");
  std::vector<SourceFile> files;
  Assimp::Importer importer;
  importer.SetIOHandler(new RecordingIo(&files));  // owned by the importer
  const unsigned flags = aiProcess_Triangulate | aiProcess_SortByPType | aiProcess_FlipUVs |
                         aiProcess_ValidateDataStructure;
  const aiScene* sc = nullptr;
  try {  // third-party code: anything it throws is still bad input
    sc = importer.ReadFile(path, flags);
  } catch (const std::exception& e) {
    throw InputError(path + ": cannot read: " + e.what());
  }
  if (!sc || !sc->mRootNode || (sc->mFlags & AI_SCENE_FLAGS_INCOMPLETE))
    throw InputError(path + ": cannot read: " + std::string(importer.GetErrorString()[0] ? importer.GetErrorString()
                                                                                      : "incomplete scene"));
  Scene s = AssimpReader(*sc, path).read();
  for (const SourceFile& f : s.files)  // what Assimp opened (the model first), then the textures
    if (std::find(files.begin(), files.end(), f) == files.end()) files.push_back(f);
  s.files = std::move(files);
  s.source = path;
  return s;
}

bool assimp_reads(const std::string& path) {
  const std::string ext = std::filesystem::path(path).extension().string();
  if (ext.size() < 2 || has_extension_ci(path, ".gltf") || has_extension_ci(path, ".glb")) return false;
  Assimp::Importer importer;
  return importer.IsExtensionSupported(ext);
}

}  // namespace occ
