// Which reader reads which model file (model_reader.hpp).
#include "common/scene/model_reader.hpp"

#include "common/scene/assimp_reader.hpp"
#include "common/scene/ply_reader.hpp"

namespace occ {

bool is_model_path(const std::string& path) { return is_ply_path(path) || assimp_reads(path); }

Scene load_model(const std::string& path) { return is_ply_path(path) ? load_ply(path) : load_with_assimp(path); }

}  // namespace occ
