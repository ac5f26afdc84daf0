// Geometry left in a mapped cache file (--geometry-budget, issue 38): where each lazily loaded
// mesh's arrays lie in the scene or LOD cache, so the GPU upload reads a mesh when a frame needs
// it instead of every process holding the whole scene. The meshes themselves are loaded released
// (Mesh::released, LodMesh::released): counts, boxes and clusters only. No GL.
#pragma once
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "common/mapped_file.hpp"

namespace occ {

// `count` elements at byte `offset` of the file (0, 0: absent). Not aligned: read with memcpy.
struct MappedArray {
  uint64_t offset = 0, count = 0, bytes = 0;
};

// A mesh's arrays in the file: a scene mesh's (objects empty) or a LOD mesh's (uvs and colours
// empty; objects per vertex for an HLOD).
struct MappedMesh {
  MappedArray positions, normals, indices, uvs, colors, objects;
};

struct MappedGeometry {
  std::string path;                  // for messages
  std::shared_ptr<MappedFile> file;  // kept open (mapped) for as long as anything streams from it
  std::vector<MappedMesh> meshes;    // per mesh of the owner: Scene::meshes, or LodData's cluster
                                     // LODs followed by its HLODs
  const uint8_t* at(const MappedArray& a) const { return file->data() + a.offset; }
  // After a mesh was copied out: its pages leave this process (not the page cache).
  void drop(const MappedMesh& m) const {
    for (const MappedArray* a : {&m.positions, &m.normals, &m.indices, &m.uvs, &m.colors, &m.objects})
      if (a->bytes) file->drop_range(a->offset, a->bytes);
  }
};

}  // namespace occ
