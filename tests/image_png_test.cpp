#include <gtest/gtest.h>

#include <filesystem>

#include "common/image.hpp"

using namespace occ;

namespace {
std::string temp_path(const std::string& name) {
  return (std::filesystem::temp_directory_path() /
          ("occ_image_test_" + std::to_string(::getpid()) + "_" + name)).string();
}
}  // namespace

TEST(Png, RoundTripKeepsEveryByteAndRowOrder) {
  Image img;
  img.width = 7;
  img.height = 3;
  for (int i = 0; i < 7 * 3 * 4; ++i) img.rgba.push_back(uint8_t(i * 37 + 11));
  const std::string path = temp_path("roundtrip.png");
  write_png(path, img);
  Image back = read_png(path);
  std::filesystem::remove(path);
  EXPECT_EQ(back.width, 7);
  EXPECT_EQ(back.height, 3);
  EXPECT_EQ(back.rgba, img.rgba);
}

TEST(Png, ErrorsNameTheFile) {
  const std::string missing = temp_path("does_not_exist.png");
  try {
    read_png(missing);
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(missing), std::string::npos) << e.what();
  }
  Image bad;  // size does not match its pixel data
  bad.width = 2;
  bad.height = 2;
  bad.rgba.resize(3);
  const std::string path = temp_path("bad.png");
  try {
    write_png(path, bad);
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
  }
  Image ok;
  ok.width = ok.height = 1;
  ok.rgba = {1, 2, 3, 4};
  EXPECT_THROW(write_png("/nonexistent-dir/x.png", ok), std::runtime_error);
}
