// Geometry left in a cache file (--geometry-budget): where each lazily loaded mesh's
// arrays lie in the scene or LOD cache, so the GPU upload reads a mesh when a frame needs it
// instead of every process holding the whole scene. The meshes themselves are loaded released
// (Mesh::released, LodMesh::released): counts, boxes and clusters only. A mesh is read with one
// pread of its arrays' span (from the page cache, after the first time): no mapping, so nothing of
// the file counts in the process's memory. No GL.
#pragma once
#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdint>
#include <cstring>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

namespace occ {

// `count` elements (`bytes` in all) at byte `offset` of the file (all 0: absent).
struct MappedArray {
  uint64_t offset = 0, count = 0, bytes = 0;
};

// A mesh's arrays in the file: a scene mesh's (objects empty) or a LOD mesh's (uvs and colours
// empty; objects per vertex for an HLOD).
struct MappedMesh {
  MappedArray positions, normals, indices, uvs, colors, objects;
};

// An open file read with pread (thread-safe: no file position).
class FileReader {
 public:
  // Throws std::runtime_error naming the path when it cannot be opened.
  explicit FileReader(std::string path) : path_(std::move(path)) {
    fd_ = ::open(path_.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd_ < 0) throw std::runtime_error(path_ + ": cannot open: " + std::strerror(errno));
  }
  ~FileReader() { ::close(fd_); }
  FileReader(const FileReader&) = delete;
  FileReader& operator=(const FileReader&) = delete;
  // bytes [offset, offset + n) into out; throws naming the file for a short or failed read.
  void read(uint64_t offset, size_t n, uint8_t* out) const {
    while (n > 0) {
      const ssize_t got = ::pread(fd_, out, n, off_t(offset));
      if (got < 0 && errno == EINTR) continue;
      if (got <= 0)
        throw std::runtime_error(path_ + ": cannot read " + std::to_string(n) + " bytes at " + std::to_string(offset) +
                                 (got < 0 ? std::string(": ") + std::strerror(errno) : ": the file is shorter"));
      out += got, offset += uint64_t(got), n -= size_t(got);
    }
  }
  const std::string& path() const { return path_; }

 private:
  std::string path_;
  int fd_ = -1;
};

struct MappedGeometry {
  // The meshes' places in the file at `path`, opened for reading; nullptr and *why when it
  // cannot be opened.
  static std::shared_ptr<const MappedGeometry> open(const std::string& path, std::vector<MappedMesh> meshes,
                                                    std::string* why) {
    auto g = std::make_shared<MappedGeometry>();
    g->meshes = std::move(meshes);
    try {
      g->file = std::make_shared<FileReader>(path);
    } catch (const std::runtime_error& e) {
      *why = e.what();
      return nullptr;
    }
    return g;
  }

  std::shared_ptr<const FileReader> file;  // open for as long as anything streams from it
  std::vector<MappedMesh> meshes;          // per mesh of the owner: Scene::meshes, or LodData's
                                           // cluster LODs followed by its HLODs
  const std::string& path() const { return file->path(); }
  // Reads the span of the file that holds all of m's arrays into buf (one read); returns the file
  // offset of buf[0].
  uint64_t read(const MappedMesh& m, std::vector<uint8_t>& buf) const {
    uint64_t begin = UINT64_MAX, end = 0;
    for (const MappedArray* a : {&m.positions, &m.normals, &m.indices, &m.uvs, &m.colors, &m.objects})
      if (a->bytes) begin = std::min(begin, a->offset), end = std::max(end, a->offset + a->bytes);
    if (end == 0) return 0;
    buf.resize(end - begin);
    file->read(begin, buf.size(), buf.data());
    return begin;
  }
};

}  // namespace occ
