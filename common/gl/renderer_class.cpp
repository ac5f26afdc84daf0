#include "common/gl/renderer_class.hpp"

#include <algorithm>
#include <cctype>
#include <string>

namespace occ {

RendererClass classify_renderer(std::string_view renderer, std::string_view vendor) {
  auto lower = [](std::string_view s) {
    std::string out(s);
    std::transform(out.begin(), out.end(), out.begin(), [](unsigned char c) { return char(std::tolower(c)); });
    return out;
  };
  const std::string r = lower(renderer), v = lower(vendor);
  // GL_RENDERER of Mesa's software drivers ("llvmpipe (LLVM 15.0.6, 256 bits)", "softpipe",
  // "Software Rasterizer" of swrast), Google's SwiftShader, Microsoft's GDI generic renderer.
  for (const char* name : {"llvmpipe", "softpipe", "software rasterizer", "swrast", "swiftshader", "gdi generic"})
    if (r.find(name) != std::string::npos) return RendererClass::software;
  if (v.find("swiftshader") != std::string::npos) return RendererClass::software;
  return RendererClass::hardware;
}

const char* renderer_class_name(RendererClass c) {
  return c == RendererClass::software ? "software" : "hardware";
}

}  // namespace occ
