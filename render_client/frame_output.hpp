// Where a renderer's frames go: DIR/frame_%05d.png (unless images are off) and DIR/stats.csv
// with one row per frame. A frame's PNG is written to a temporary name and renamed, so a
// frame file that exists is complete.
#pragma once
#include <fstream>
#include <string>
#include <vector>

#include "common/scene/hierarchy.hpp"
#include "common/image.hpp"

namespace occ {

class FrameOutput {
 public:
  // dir empty = nothing written. Creates dir. columns: the stats.csv header.
  FrameOutput(const std::string& dir, bool images, std::vector<std::string> columns);
  void write_frame(uint32_t frame, const Image& img);
  // One per column, in order: the numbers, then `text` (words without commas) for the last columns.
  void write_row(const std::vector<double>& values, const std::vector<std::string>& text = {});
  // --images items: DIR/items_%05d.png, an item buffer of the frame (RGBA8 = a little-endian u32 id per
  // pixel), DIR/depth_%05d.png its depth (the float's bits, the same way; `depth` as GL reads it,
  // bottom row first), and once DIR/items.txt, the ids' space (render_client/tools/item_diff.hpp).
  void write_items(uint32_t frame, const Image& ids, const std::vector<float>& depth);
  void write_item_space(const Hierarchy& h);
  bool writes_images() const { return !dir_.empty() && images_; }
  const std::string& dir() const { return dir_; }

 private:
  std::string dir_;
  bool images_;
  size_t columns_;
  std::ofstream csv_;
};

std::string frame_file_name(uint32_t frame);  // "frame_00042.png"

}  // namespace occ
