#include "render_client/frame_output.hpp"

#include <cmath>
#include <cstdio>
#include <filesystem>

#include "common/error.hpp"
#include "render_client/tools/item_diff.hpp"

namespace occ {

std::string frame_file_name(uint32_t frame) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "frame_%05u.png", frame);
  return buf;
}

FrameOutput::FrameOutput(const std::string& dir, bool images, std::vector<std::string> columns)
    : dir_(dir), images_(images), columns_(columns.size()) {
  if (dir_.empty()) return;
  std::error_code ec;
  std::filesystem::create_directories(dir_, ec);
  if (ec) throw InputError("--out '" + dir_ + "': cannot create directory: " + ec.message());
  csv_.open(dir_ + "/stats.csv");
  if (!csv_) throw InputError("--out '" + dir_ + "': cannot write stats.csv");
  for (size_t i = 0; i < columns.size(); ++i) csv_ << (i ? "," : "") << columns[i];
  csv_ << "\n";
}

namespace {

void write_png_atomically(const std::string& final_path, const Image& img) {
  const std::string tmp = final_path + ".tmp.png";
  write_png(tmp, img);
  std::filesystem::rename(tmp, final_path);
}

}  // namespace

void FrameOutput::write_frame(uint32_t frame, const Image& img) {
  if (writes_images()) write_png_atomically(dir_ + "/" + frame_file_name(frame), img);
}

void FrameOutput::write_items(uint32_t frame, const Image& ids, const std::vector<float>& depth) {
  if (dir_.empty()) return;
  char buf[32];
  std::snprintf(buf, sizeof buf, "items_%05u.png", frame);
  write_png_atomically(dir_ + "/" + buf, ids);
  std::snprintf(buf, sizeof buf, "depth_%05u.png", frame);
  write_png_atomically(dir_ + "/" + buf, encode_depth(ids.width, ids.height, depth));
}

void FrameOutput::write_item_space(const Hierarchy& h) {
  if (!dir_.empty()) ItemSpace::of(h).write(dir_ + "/items.txt");
}

void FrameOutput::write_row(const std::vector<double>& values, const std::vector<std::string>& text) {
  if (dir_.empty()) return;
  for (size_t i = 0; i < values.size() && i < columns_; ++i) {
    double v = values[i];
    if (v == std::floor(v) && std::abs(v) < 1e15)
      csv_ << (i ? "," : "") << static_cast<long long>(v);
    else
      csv_ << (i ? "," : "") << v;
  }
  for (size_t i = 0; i < text.size() && values.size() + i < columns_; ++i) csv_ << (values.size() + i ? "," : "") << text[i];
  csv_ << "\n";
  csv_.flush();
}

}  // namespace occ
