#include "common/image.hpp"

#include <stb/stb_image.h>
#include <stb/stb_image_write.h>

#include <memory>
#include <stdexcept>

namespace occ {

void write_png(const std::string& path, const Image& img) {
  if (img.width <= 0 || img.height <= 0 || img.rgba.size() != size_t(img.width) * img.height * 4)
    throw std::runtime_error(path + ": cannot write PNG: image is " + std::to_string(img.width) +
                             "x" + std::to_string(img.height) + " with " +
                             std::to_string(img.rgba.size()) + " bytes");
  if (!stbi_write_png(path.c_str(), img.width, img.height, 4, img.rgba.data(), img.width * 4))
    throw std::runtime_error(path + ": cannot write PNG");
}

Image read_png(const std::string& path) {
  int w = 0, h = 0, channels = 0;
  std::unique_ptr<stbi_uc, void (*)(void*)> data(stbi_load(path.c_str(), &w, &h, &channels, 4),
                                                 stbi_image_free);
  if (!data) throw std::runtime_error(path + ": cannot read PNG: " + stbi_failure_reason());
  Image img;
  img.width = w;
  img.height = h;
  img.rgba.assign(data.get(), data.get() + size_t(w) * h * 4);
  return img;
}

}  // namespace occ
