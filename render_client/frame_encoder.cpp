#include "render_client/frame_encoder.hpp"

#include <turbojpeg.h>
#include <zlib.h>

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

void put_u32(std::vector<uint8_t>& out, uint32_t v) {
  for (int s = 24; s >= 0; s -= 8) out.push_back(uint8_t(v >> s));
}

// One PNG chunk: length, type, data, CRC of type and data.
void put_chunk(std::vector<uint8_t>& out, const char* type, const uint8_t* data, size_t n) {
  put_u32(out, uint32_t(n));
  const size_t start = out.size();
  out.insert(out.end(), type, type + 4);
  out.insert(out.end(), data, data + n);
  put_u32(out, uint32_t(crc32(0, out.data() + start, uInt(n + 4))));
}

// RGBA8 PNG, every row with the Sub filter, deflated by zlib at its fastest level: lossless,
// larger than stb's default level and many times quicker to write.
class PngEncoder : public FrameEncoder {
 public:
  std::vector<uint8_t> encode(const Image& img) override {
    if (img.width <= 0 || img.height <= 0 || img.rgba.size() != size_t(img.width) * img.height * 4)
      throw std::runtime_error("PNG: image size does not match its pixels");
    const size_t row = size_t(img.width) * 4;
    raw_.resize((row + 1) * size_t(img.height));
    for (size_t y = 0; y < size_t(img.height); ++y) {
      const uint8_t* src = img.rgba.data() + y * row;
      uint8_t* dst = raw_.data() + y * (row + 1);
      dst[0] = 1;  // Sub: each byte minus the same channel of the pixel to its left
      for (size_t i = 0; i < row; ++i) dst[1 + i] = uint8_t(src[i] - (i >= 4 ? src[i - 4] : 0));
    }
    uLongf packed = compressBound(uLong(raw_.size()));
    deflated_.resize(packed);
    if (compress2(deflated_.data(), &packed, raw_.data(), uLong(raw_.size()), Z_BEST_SPEED) != Z_OK)
      throw std::runtime_error("PNG: zlib compress2 failed");
    static const uint8_t kSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
    std::vector<uint8_t> out(kSignature, kSignature + 8), ihdr;
    put_u32(ihdr, uint32_t(img.width));
    put_u32(ihdr, uint32_t(img.height));
    ihdr.insert(ihdr.end(), {8, 6, 0, 0, 0});  // 8 bits, RGBA, deflate, adaptive filters, no interlace
    put_chunk(out, "IHDR", ihdr.data(), ihdr.size());
    put_chunk(out, "IDAT", deflated_.data(), packed);
    put_chunk(out, "IEND", nullptr, 0);
    return out;
  }
  const char* format() const override { return "png"; }

 private:
  std::vector<uint8_t> raw_, deflated_;  // kept between frames: no allocation per frame
};

}  // namespace

std::unique_ptr<FrameEncoder> make_jpeg_encoder(int quality) { return std::make_unique<JpegEncoder>(quality); }
std::unique_ptr<FrameEncoder> make_png_encoder() { return std::make_unique<PngEncoder>(); }

}  // namespace occ
