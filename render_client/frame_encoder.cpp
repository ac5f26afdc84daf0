#include "render_client/frame_encoder.hpp"

#include <turbojpeg.h>

#include <stdexcept>
#include <string>

namespace occ {

namespace {

class JpegEncoder : public FrameEncoder {
 public:
  explicit JpegEncoder(int quality) : quality_(quality), tj_(tjInitCompress()) {
    if (!tj_) throw std::runtime_error(std::string("TurboJPEG: cannot start the compressor: ") + tjGetErrorStr());
  }
  ~JpegEncoder() override { tjDestroy(tj_); }
  JpegEncoder(const JpegEncoder&) = delete;
  JpegEncoder& operator=(const JpegEncoder&) = delete;

  std::vector<uint8_t> encode(const Image& img) override {
    if (img.width <= 0 || img.height <= 0 || img.rgba.size() != size_t(img.width) * img.height * 4)
      throw std::runtime_error("TurboJPEG: image size does not match its pixels");
    unsigned char* buf = nullptr;
    unsigned long size = 0;
    if (tjCompress2(tj_, img.rgba.data(), img.width, img.width * 4, img.height, TJPF_RGBA, &buf, &size, TJSAMP_420,
                    quality_, TJFLAG_FASTDCT) != 0) {
      if (buf) tjFree(buf);
      throw std::runtime_error(std::string("TurboJPEG: ") + tjGetErrorStr2(tj_));
    }
    std::vector<uint8_t> out(buf, buf + size);
    tjFree(buf);
    return out;
  }
  const char* format() const override { return "jpeg"; }

 private:
  int quality_;
  tjhandle tj_;
};

class PngEncoder : public FrameEncoder {
 public:
  std::vector<uint8_t> encode(const Image& img) override { return encode_png(img); }
  const char* format() const override { return "png"; }
};

}  // namespace

std::unique_ptr<FrameEncoder> make_jpeg_encoder(int quality) { return std::make_unique<JpegEncoder>(quality); }
std::unique_ptr<FrameEncoder> make_png_encoder() { return std::make_unique<PngEncoder>(); }

}  // namespace occ
