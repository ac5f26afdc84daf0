// Frame encoders for render_client --web: RGBA frames to the bytes a browser decodes. JPEG
// (TurboJPEG, lossy, for frames while the camera moves) and PNG (zlib, lossless, the frame once
// the camera is still). An encoder is used by one thread at a time.
#pragma once
#include <cstdint>
#include <memory>
#include <vector>

#include "common/image.hpp"

namespace occ {

class FrameEncoder {
 public:
  virtual ~FrameEncoder() = default;
  // The encoded frame; throws std::runtime_error naming the encoder when it fails.
  virtual std::vector<uint8_t> encode(const Image& img) = 0;
  virtual const char* format() const = 0;  // "jpeg" or "png": the page's name for it
};

// quality 1..100 (TurboJPEG's scale), 4:2:0 chroma, alpha dropped.
std::unique_ptr<FrameEncoder> make_jpeg_encoder(int quality);
std::unique_ptr<FrameEncoder> make_png_encoder();

}  // namespace occ
