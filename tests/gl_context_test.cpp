#include <gtest/gtest.h>

#include <thread>

#include "common/error.hpp"
#include "common/gl/context.hpp"

namespace occ {
inline void PrintTo(GlBackend b, std::ostream* os) {
  *os << (b == GlBackend::Egl ? "egl" : b == GlBackend::OSMesa ? "osmesa" : "auto");
}
}  // namespace occ

using namespace occ;

TEST(GlBackend, ParsesNamesAndRejectsUnknown) {
  EXPECT_EQ(parse_gl_backend("auto"), GlBackend::Auto);
  EXPECT_EQ(parse_gl_backend("egl"), GlBackend::Egl);
  EXPECT_EQ(parse_gl_backend("osmesa"), GlBackend::OSMesa);
  try {
    parse_gl_backend("vulkan");
    FAIL() << "no exception";
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "--gl 'vulkan': expected egl, osmesa or auto");
  }
}

TEST(GlContext, RejectsZeroSizedFramebuffer) {
  EXPECT_THROW(GlContext::create(GlBackend::Auto, 0, 16), InputError);
}

class GlContextBackend : public testing::TestWithParam<GlBackend> {};

TEST_P(GlContextBackend, ClearsAndReadsBackColourTopRowFirst) {
  auto ctx = GlContext::create(GetParam(), 32, 16);
  EXPECT_EQ(ctx->width(), 32);
  EXPECT_EQ(ctx->height(), 16);
  EXPECT_FALSE(ctx->renderer().empty());
  EXPECT_EQ(std::string(ctx->backend_name()).substr(0, 3), GetParam() == GlBackend::Egl ? "egl" : "osm");
  const GlApi& gl = ctx->gl();
  gl.ClearColor(1.0f, 0.0f, 0.0f, 1.0f);
  gl.Clear(GL_COLOR_BUFFER_BIT);
  // Paint the bottom half green: GL's origin is bottom-left, the image's first row is the top.
  gl.Enable(GL_SCISSOR_TEST);
  gl.Scissor(0, 0, 32, 8);
  gl.ClearColor(0.0f, 1.0f, 0.0f, 1.0f);
  gl.Clear(GL_COLOR_BUFFER_BIT);
  gl.Disable(GL_SCISSOR_TEST);
  Image img = ctx->read_rgba();
  ASSERT_EQ(img.rgba.size(), 32u * 16u * 4u);
  auto px = [&](int x, int y) { return &img.rgba[(size_t(y) * 32 + x) * 4]; };
  EXPECT_EQ(px(3, 2)[0], 255);  // top: red
  EXPECT_EQ(px(3, 2)[1], 0);
  EXPECT_EQ(px(3, 13)[0], 0);  // bottom: green
  EXPECT_EQ(px(3, 13)[1], 255);
  EXPECT_EQ(gl.GetError(), GLenum(GL_NO_ERROR));
}

TEST_P(GlContextBackend, CanBeMovedBetweenThreadsAndRecreated) {
  for (int round = 0; round < 2; ++round) {
    auto ctx = GlContext::create(GetParam(), 8, 8);
    ctx->release_current();
    std::string renderer;
    std::thread t([&] {
      ctx->make_current();
      renderer = ctx->renderer();
      ctx->release_current();
    });
    t.join();
    ctx->make_current();
    EXPECT_EQ(renderer, ctx->renderer());
  }
}

INSTANTIATE_TEST_SUITE_P(Backends, GlContextBackend, testing::Values(GlBackend::Egl, GlBackend::OSMesa),
                         [](const auto& info) { return info.param == GlBackend::Egl ? "Egl" : "OSMesa"; });

// The renderer class: from GL_RENDERER and GL_VENDOR alone.
TEST(RendererClass, SoftwareRasterisersAndGpus) {
  EXPECT_EQ(classify_renderer("llvmpipe (LLVM 15.0.6, 256 bits)", "Mesa/X.org"), RendererClass::software);
  EXPECT_EQ(classify_renderer("softpipe", "Mesa"), RendererClass::software);
  EXPECT_EQ(classify_renderer("Software Rasterizer", "Mesa Project"), RendererClass::software);
  EXPECT_EQ(classify_renderer("SwiftShader Device (Subzero)", "Google Inc."), RendererClass::software);
  EXPECT_EQ(classify_renderer("NVIDIA H200/PCIe/SSE2", "NVIDIA Corporation"), RendererClass::hardware);
  EXPECT_EQ(classify_renderer("AMD Radeon RX 7900 XTX (radeonsi, navi31, LLVM 15.0.6, DRM 3.54)", "AMD"),
            RendererClass::hardware);
  EXPECT_EQ(classify_renderer("Mesa Intel(R) UHD Graphics 630 (CFL GT2)", "Intel"), RendererClass::hardware);
  EXPECT_STREQ(renderer_class_name(RendererClass::software), "software");
  EXPECT_STREQ(renderer_class_name(RendererClass::hardware), "hardware");
}

TEST_P(GlContextBackend, KnowsItsRendererClass) {
  auto ctx = GlContext::create(GetParam(), 8, 8);
  EXPECT_FALSE(ctx->vendor().empty());
  EXPECT_EQ(ctx->renderer_class(), classify_renderer(ctx->renderer(), ctx->vendor()));
  // This machine has no GPU: llvmpipe on every back end.
  if (ctx->renderer().find("llvmpipe") != std::string::npos) {
    EXPECT_EQ(ctx->renderer_class(), RendererClass::software);
  }
}
