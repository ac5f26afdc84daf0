// Which kind of renderer a context got, from its GL_RENDERER and GL_VENDOR strings alone (no GL
// here): a software rasteriser (Mesa's llvmpipe or softpipe, OSMesa, SwiftShader, ...) or a
// hardware GPU. The start-up line names it (startup.hpp); GlContext::renderer_class() gives it
// for choosing defaults by renderer.
#pragma once
#include <string_view>

namespace occ {

enum class RendererClass { software, hardware };

RendererClass classify_renderer(std::string_view renderer, std::string_view vendor);
const char* renderer_class_name(RendererClass c);  // "software", "hardware"

}  // namespace occ
