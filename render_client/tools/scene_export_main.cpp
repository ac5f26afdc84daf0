// scene_export: writes the scene that --scene SPEC loads as glTF (FILE.gltf + FILE.bin), the
// geometry and placement every occswitch process draws, generated scenes included: for another
// renderer (bench.sh's OpenSceneGraph peer) or to keep a generated scene as a file.
#include <iostream>

#include "common/cli.hpp"
#include "common/error.hpp"
#include "common/setup/scene_setup.hpp"
#include "render_client/tools/scene_export.hpp"

int main(int argc, char** argv) {
  return occ::run_main([&] {
    occ::SceneOptions scene;
    std::string out;
    occ::Cli cli("scene_export", "--scene SPEC --out FILE.gltf [options]",
                 "Writes the scene --scene loads as glTF 2.0 (FILE.gltf + FILE.bin beside it): geometry and\n"
                 "placement only, one mesh per scene mesh, one node per object.");
    occ::add_scene_options(cli, scene);
    cli.group(occ::CliGroup::output);
    cli.option("out", &out, "FILE.gltf", "the glTF file to write (FILE.bin is written beside it)");
    if (!cli.parse(argc, argv)) return 0;
    if (out.empty()) throw occ::InputError("--out FILE.gltf is required");
    const occ::LoadedScene ls = occ::load_and_build(scene, "scene_export");
    occ::save_gltf(ls.scene, out);
    std::cerr << "scene_export: wrote " << out << (ls.scene.mapped ? " (meshes read back from the scene cache)" : "")
              << "\n";
    return 0;
  });
}
