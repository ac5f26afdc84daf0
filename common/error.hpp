// Error type for bad external input (scene files, paths, flags). The message says what and
// where, e.g. "scene.glb: node 17: mesh 9 out of range (8 meshes)"; main() prints it as one
// "error: ..." line and exits non-zero.
#pragma once
#include <stdexcept>
#include <string>

namespace occ {

struct InputError : std::runtime_error {
  explicit InputError(const std::string& what) : std::runtime_error(what) {}
};

}  // namespace occ
