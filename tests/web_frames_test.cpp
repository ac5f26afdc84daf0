// What render_client --web sends (render_client/web_display.hpp, frame_encoder.hpp): the PNG is
// lossless, the JPEG close to the frame, the header names the format and the camera as a --path
// row that replays the camera (to the rounding of its orientation).
#include <turbojpeg.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <gtest/gtest.h>

#include "common/camera_path.hpp"
#include "render_client/frame_encoder.hpp"
#include "render_client/web_display.hpp"

using namespace occ;

namespace {

Image gradient(int w, int h) {
  Image img{w, h, std::vector<uint8_t>(size_t(w) * h * 4)};
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      uint8_t* p = &img.rgba[(size_t(y) * w + x) * 4];
      p[0] = uint8_t(x * 255 / w), p[1] = uint8_t(y * 255 / h), p[2] = uint8_t((x + y) & 0xff), p[3] = 255;
    }
  return img;
}

std::vector<double> numbers(const std::string& csv) {
  std::vector<double> v;
  std::stringstream in(csv);
  for (std::string cell; std::getline(in, cell, ',');) v.push_back(std::stod(cell));
  return v;
}

std::string temp_file(const char* name) {
  return (std::filesystem::temp_directory_path() / (std::string(name) + std::to_string(::getpid()))).string();
}

TEST(WebFrames, PngIsLossless) {
  const Image img = gradient(67, 41);
  const std::vector<uint8_t> png = make_png_encoder()->encode(img);
  const std::string f = temp_file("occ_web_png_");
  std::ofstream(f, std::ios::binary).write(reinterpret_cast<const char*>(png.data()), std::streamsize(png.size()));
  const Image back = read_png(f);
  std::filesystem::remove(f);
  EXPECT_EQ(back.width, 67);
  EXPECT_EQ(back.height, 41);
  EXPECT_EQ(back.rgba, img.rgba);
}

TEST(WebFrames, JpegDecodesCloseToTheFrame) {
  const Image img = gradient(64, 48);
  auto enc = make_jpeg_encoder(80);
  EXPECT_STREQ(enc->format(), "jpeg");
  const std::vector<uint8_t> jpg = enc->encode(img);
  ASSERT_GT(jpg.size(), 4u);
  EXPECT_EQ(jpg[0], 0xff);
  EXPECT_EQ(jpg[1], 0xd8);  // SOI
  tjhandle tj = tjInitDecompress();
  std::vector<uint8_t> rgba(img.rgba.size());
  ASSERT_EQ(tjDecompress2(tj, jpg.data(), jpg.size(), rgba.data(), 64, 0, 48, TJPF_RGBA, 0), 0) << tjGetErrorStr2(tj);
  tjDestroy(tj);
  double err = 0;
  for (size_t i = 0; i < rgba.size(); ++i) err += std::abs(int(rgba[i]) - int(img.rgba[i]));
  EXPECT_LT(err / double(rgba.size()), 4.0) << "mean absolute error per channel";
  EXPECT_THROW(enc->encode(Image{2, 2, {}}), std::runtime_error);
}

TEST(WebFrames, TheHeaderCarriesACameraThatReplaysExactly) {
  Aabb box;
  box.grow(glm::dvec3(-3.3, 0, -7.1));
  box.grow(glm::dvec3(11.9, 4.2, 5.5));
  ShownFrame f;
  f.camera = load_camera_path("orbit:7", box, {128, 96})[3];
  f.index = 12;
  f.input_seq = 99;
  f.stats.visible = 3;
  f.stats.leaves = 4;
  const std::string h = web_frame_header(f, "png", 128, 96, 1.5, 7.25);
  const std::string row = camera_csv_fields(f.camera);
  EXPECT_NE(h.find("\"format\":\"png\""), std::string::npos) << h;
  EXPECT_NE(h.find("\"frame\":12,\"seq\":99,\"width\":128,\"height\":96"), std::string::npos) << h;
  EXPECT_NE(h.find("\"culled_pct\":25.00"), std::string::npos) << h;
  EXPECT_NE(h.find("\"encode_ms\":1.500,\"input_ms\":7.25"), std::string::npos) << h;
  EXPECT_NE(h.find("\"camera\":\"" + row + "\""), std::string::npos) << h;
  // The row, as a --path file, gives back the same camera (so the reference renders that frame).
  const std::string file = temp_file("occ_web_cam_") + ".csv";
  std::ofstream(file) << "frame,eye_x,eye_y,eye_z,target_x,target_y,target_z,up_x,up_y,up_z,fovy_deg,near,far\n0," << row
                      << "\n";
  const Camera back = load_camera_path(file, box, {128, 96})[0];
  std::filesystem::remove(file);
  // Eye, fov, near and far to the bit; the view direction and up to the rounding of the
  // orientation rebuilt from them (a few units in the last place).
  const std::vector<double> a = numbers(row), b = numbers(camera_csv_fields(back));
  ASSERT_EQ(a.size(), 12u);
  ASSERT_EQ(b.size(), 12u);
  for (size_t i = 0; i < a.size(); ++i) {
    if (i < 3 || i >= 9)
      EXPECT_EQ(a[i], b[i]) << "field " << i;
    else
      EXPECT_NEAR(a[i], b[i], 1e-13 * std::max(1.0, std::abs(a[i]))) << "field " << i;
  }
}

}  // namespace
