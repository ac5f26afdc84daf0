#include "render_client/tools/scene_export.hpp"

#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <vector>

#include "common/error.hpp"

namespace occ {

namespace {

// Appends raw little-endian bytes (this build is little-endian, as glTF is) at a 4-byte boundary.
template <class T>
size_t append(std::vector<char>& bin, const std::vector<T>& v) {
  while (bin.size() % 4) bin.push_back(0);
  const size_t offset = bin.size();
  bin.resize(offset + v.size() * sizeof(T));
  std::memcpy(bin.data() + offset, v.data(), v.size() * sizeof(T));
  return offset;
}

std::string num(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.17g", v);
  return b;
}

}  // namespace

void save_gltf(const Scene& scene, const std::string& gltf_path) {
  namespace fs = std::filesystem;
  const fs::path bin_path = fs::path(gltf_path).replace_extension(".bin");
  std::vector<char> bin;
  std::ostringstream views, accessors, meshes, nodes, roots;
  std::vector<int> mesh_index(scene.meshes.size(), -1);
  int n_views = 0, n_meshes = 0;
  auto view = [&](size_t offset, size_t bytes, int target) {
    views << (n_views ? "," : "") << "{\"buffer\":0,\"byteOffset\":" << offset << ",\"byteLength\":" << bytes
          << ",\"target\":" << target << "}";
    return n_views++;
  };
  Mesh read_back;  // a mesh of a scene read lazily from its cache (--geometry-budget)
  for (size_t m = 0; m < scene.meshes.size(); ++m) {
    const bool mapped = scene.mapped && scene.meshes[m].released;
    if (mapped) read_back = read_mapped_mesh(scene, uint32_t(m));
    const Mesh& mesh = mapped ? read_back : scene.meshes[m];
    if (mesh.indices.size() < 3 || mesh.positions.empty()) continue;
    const Aabb box = mesh.box();
    const int pos = view(append(bin, mesh.positions), mesh.positions.size() * 12, 34962);
    const int nrm = view(append(bin, mesh.normals), mesh.normals.size() * 12, 34962);
    const int idx = view(append(bin, mesh.indices), mesh.indices.size() * 4, 34963);
    const int a = 3 * n_meshes;
    accessors << (n_meshes ? "," : "") << "{\"bufferView\":" << pos << ",\"componentType\":5126,\"count\":"
              << mesh.positions.size() << ",\"type\":\"VEC3\",\"min\":[" << num(box.min.x) << "," << num(box.min.y)
              << "," << num(box.min.z) << "],\"max\":[" << num(box.max.x) << "," << num(box.max.y) << ","
              << num(box.max.z) << "]},{\"bufferView\":" << nrm << ",\"componentType\":5126,\"count\":"
              << mesh.normals.size() << ",\"type\":\"VEC3\"},{\"bufferView\":" << idx
              << ",\"componentType\":5125,\"count\":" << mesh.indices.size() << ",\"type\":\"SCALAR\"}";
    // A flat mesh goes without NORMAL, so that it is read back flat (its normals stay unused).
    meshes << (n_meshes ? "," : "") << "{\"primitives\":[{\"attributes\":{\"POSITION\":" << a
           << (mesh.flat ? "" : ",\"NORMAL\":" + std::to_string(a + 1)) << "},\"indices\":" << a + 2
           << ",\"material\":0,\"mode\":4}]}";
    mesh_index[m] = n_meshes++;
  }
  int n_nodes = 0;
  for (const Object& o : scene.objects) {
    if (o.mesh >= mesh_index.size() || mesh_index[o.mesh] < 0) continue;
    nodes << (n_nodes ? "," : "") << "{\"mesh\":" << mesh_index[o.mesh] << ",\"matrix\":[";
    for (int c = 0; c < 4; ++c)
      for (int r = 0; r < 4; ++r) nodes << (c || r ? "," : "") << num(o.transform[c][r]);
    nodes << "]}";
    roots << (n_nodes ? "," : "") << n_nodes;
    ++n_nodes;
  }
  std::ofstream b(bin_path, std::ios::binary);
  b.write(bin.data(), std::streamsize(bin.size()));
  if (!b) throw InputError(bin_path.string() + ": cannot write the glTF buffer");
  std::ofstream g(gltf_path);
  g << "{\"asset\":{\"version\":\"2.0\",\"generator\":\"occswitch scene_export\"},"
    << "\"scene\":0,\"scenes\":[{\"nodes\":[" << roots.str() << "]}],\"nodes\":[" << nodes.str()
    // Generated scenes have no materials: per-object colours, both sides drawn. Material 0 says
    // so (an occswitch extra; other readers see a white double-sided material).
    << "],\"materials\":[{\"name\":\"occswitch object colour\",\"doubleSided\":true,"
       "\"extras\":{\"occswitch_object_colour\":true}}]"
    << ",\"meshes\":[" << meshes.str() << "],\"accessors\":[" << accessors.str() << "],\"bufferViews\":["
    << views.str() << "],\"buffers\":[{\"uri\":\"" << bin_path.filename().string() << "\",\"byteLength\":"
    << bin.size() << "}]}\n";
  if (!g) throw InputError(gltf_path + ": cannot write the glTF file");
}

}  // namespace occ
