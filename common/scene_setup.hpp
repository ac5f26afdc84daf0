// The scene every process builds identically: --scene spec + hierarchy build parameters.
// Shared by render_client, switch_node and the tools so flags and messages are the same.
#pragma once
#include <string>

#include "common/cli.hpp"
#include "common/hierarchy.hpp"
#include "common/scene.hpp"

namespace occ {

struct SceneOptions {
  std::string spec = "city";
  BuildParams build;
};

void add_scene_options(Cli& cli, SceneOptions& opts);

struct LoadedScene {
  Scene scene;
  Hierarchy hierarchy;
};

// Loads/generates the scene and builds the hierarchy; prints one summary line to stderr
// prefixed by `who` ("scene: city: 6400 objects, 2.1M triangles, ..."). Throws InputError.
LoadedScene load_and_build(const SceneOptions& opts, const std::string& who);

}  // namespace occ
