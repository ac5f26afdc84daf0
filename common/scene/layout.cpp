// Grid layouts of copies of an asset (layout.hpp).
#include "common/scene/layout.hpp"

#include <glm/gtc/matrix_transform.hpp>
#include <string>

#include "common/scene/scene_shapes.hpp"

namespace occ {

Scene layout_grid(const Scene& asset, int nx, int nz, double gap) {
  check_range("layout", "copies", nx, 1, kMaxLayoutCopies);
  check_range("layout", "copies", nz, 1, kMaxLayoutCopies);
  Scene scene;
  scene.source = "layout " + std::to_string(nx) + "x" + std::to_string(nz) + " of " + asset.source;
  scene.meshes = asset.meshes;
  scene.materials = asset.materials;
  scene.textures = asset.textures;
  scene.images = asset.images;
  const glm::dvec3 spacing = asset.bounds().extent() * (1.0 + gap);
  scene.objects.reserve(size_t(nx) * size_t(nz) * asset.objects.size());
  for (int i = 0; i < nx; ++i)
    for (int j = 0; j < nz; ++j) {
      const glm::dmat4 t = glm::translate(glm::dmat4(1.0), glm::dvec3(i * spacing.x, 0, j * spacing.z));
      const std::string prefix = "copy " + std::to_string(i) + "," + std::to_string(j) + "/";
      for (const Object& o : asset.objects)
        scene.objects.push_back(Object{o.mesh, t * o.transform, prefix + o.name});
    }
  return scene;
}

}  // namespace occ
