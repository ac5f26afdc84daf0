// Which reader reads which model file (model_reader.hpp).
#include "common/scene/model_reader.hpp"

#include "common/scene/assimp_reader.hpp"
#include "common/scene/model_mesh.hpp"
#include "common/scene/obj_reader.hpp"
#include "common/scene/ply_reader.hpp"

namespace occ {

bool is_model_path(const std::string& path) { return is_ply_path(path) || assimp_reads(path); }

Scene load_model(const std::string& path) {
  if (is_ply_path(path)) return load_ply(path);
  if (has_extension_ci(path, ".obj")) return load_obj(path);
  return load_with_assimp(path);
}

}  // namespace occ
