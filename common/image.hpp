// RGBA8 images and PNG files (stb_image / stb_image_write from Debian's libstb). No GL.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

namespace occ {

struct Image {
  int width = 0;
  int height = 0;
  std::vector<uint8_t> rgba;  // top row first, 4 bytes per pixel
};

// Throws std::runtime_error naming the file on failure.
void write_png(const std::string& path, const Image& img);
Image read_png(const std::string& path);

}  // namespace occ
