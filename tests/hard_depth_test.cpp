// Extreme near/far: near 1e-3, far 1e6. Measures what a conventional depth buffer
// would do ("before") against what the renderer does ("after": reverse-Z, GL_DEPTH_COMPONENT32F,
// glClipControl(GL_LOWER_LEFT, GL_ZERO_TO_ONE), GL_GREATER, cleared to 0, occ::Camera's
// projection), on pairs of full-screen planes at distance d and d * (1 + gap): the nearer plane
// must win every pixel. Wrong pixels (the farther plane showing: z-fighting, or an occluder
// hiding what is in front of it, which is how an occlusion query would falsely cull) are printed
// as figures for every configuration and asserted to be zero for the one the renderer uses.
#include <gtest/gtest.h>

#include <cstdio>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/type_ptr.hpp>
#include <iostream>

#include "common/camera.hpp"
#include "common/gl/context.hpp"
#include "common/gl/shader.hpp"

using namespace occ;

namespace {

constexpr int kW = 128, kH = 32;
constexpr double kNear = 1e-3, kFar = 1e6, kFovyDeg = 60.0;

const char* const kQuadVertex = R"(#version 450 core
uniform mat4 u_projection;
uniform vec3 u_min;   // view-space rectangle x/y range at depth z = u_min.z
uniform vec3 u_max;
const vec2 kCorners[6] = vec2[6](vec2(0, 0), vec2(1, 0), vec2(1, 1), vec2(0, 0), vec2(1, 1), vec2(0, 1));
void main() {
  vec2 c = kCorners[gl_VertexID];
  gl_Position = u_projection * vec4(mix(u_min.xy, u_max.xy, c), u_min.z, 1.0);
}
)";
const char* const kQuadFragment = R"(#version 450 core
uniform vec3 u_color;
out vec4 out_color;
void main() { out_color = vec4(u_color, 1.0); }
)";

struct Config {
  const char* name;
  GLenum depth_format;
  bool reverse_z;
};

class DepthPrecision {
 public:
  DepthPrecision() : ctx_(GlContext::create(GlBackend::Auto, kW, kH)), gl_(ctx_->gl()) {
    program_ = link_program(gl_, kQuadVertex, kQuadFragment);
    proj_loc_ = gl_.GetUniformLocation(program_, "u_projection");
    min_loc_ = gl_.GetUniformLocation(program_, "u_min");
    max_loc_ = gl_.GetUniformLocation(program_, "u_max");
    color_loc_ = gl_.GetUniformLocation(program_, "u_color");
    gl_.CreateVertexArrays(1, &vao_);
  }
  ~DepthPrecision() {
    gl_.DeleteVertexArrays(1, &vao_);
    gl_.DeleteProgram(program_);
    // The context's own framebuffer and state are restored for whoever renders next.
    gl_.ClipControl(GL_LOWER_LEFT, GL_ZERO_TO_ONE);
    gl_.DepthFunc(GL_GREATER);
    gl_.ClearDepth(0.0);
  }

  // Pixels where the farther plane (d * (1 + gap)) shows instead of the nearer one (d), in the
  // given draw order (near_first: the farther plane must fail the depth test; otherwise the
  // nearer must pass it).
  int wrong_pixels(const Config& cfg, double d, double gap, bool near_first) {
    GLuint fbo = 0, rb[2] = {};
    gl_.CreateFramebuffers(1, &fbo);
    gl_.CreateRenderbuffers(2, rb);
    gl_.NamedRenderbufferStorage(rb[0], GL_RGBA8, kW, kH);
    gl_.NamedRenderbufferStorage(rb[1], cfg.depth_format, kW, kH);
    gl_.NamedFramebufferRenderbuffer(fbo, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, rb[0]);
    gl_.NamedFramebufferRenderbuffer(fbo, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, rb[1]);
    EXPECT_EQ(gl_.CheckNamedFramebufferStatus(fbo, GL_FRAMEBUFFER), GLenum(GL_FRAMEBUFFER_COMPLETE));
    gl_.BindFramebuffer(GL_FRAMEBUFFER, fbo);
    gl_.Viewport(0, 0, kW, kH);

    glm::mat4 projection;
    if (cfg.reverse_z) {
      Camera cam;
      cam.fovy_rad = glm::radians(kFovyDeg);
      cam.aspect = double(kW) / kH;
      cam.near_dist = kNear;
      cam.far_dist = kFar;
      projection = glm::mat4(cam.projection());
      gl_.ClipControl(GL_LOWER_LEFT, GL_ZERO_TO_ONE);
      gl_.DepthFunc(GL_GREATER);
      gl_.ClearDepth(0.0);
    } else {  // the textbook set-up: OpenGL's [-1, 1] clip z, less-than, cleared to 1
      projection = glm::mat4(glm::perspective(glm::radians(kFovyDeg), double(kW) / kH, kNear, kFar));
      gl_.ClipControl(GL_LOWER_LEFT, GL_NEGATIVE_ONE_TO_ONE);
      gl_.DepthFunc(GL_LESS);
      gl_.ClearDepth(1.0);
    }
    gl_.Enable(GL_DEPTH_TEST);
    gl_.DepthMask(GL_TRUE);
    gl_.ColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
    gl_.ClearColor(0, 0, 0, 1);
    gl_.Clear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    gl_.UseProgram(program_);
    gl_.BindVertexArray(vao_);
    gl_.ProgramUniformMatrix4fv(program_, proj_loc_, 1, GL_FALSE, glm::value_ptr(projection));
    auto plane = [&](double z, float r, float g) {
      const double half_h = 2.0 * z * std::tan(glm::radians(kFovyDeg) / 2), half_w = half_h * kW / kH;
      gl_.ProgramUniform3f(program_, min_loc_, float(-half_w), float(-half_h), float(-z));
      gl_.ProgramUniform3f(program_, max_loc_, float(half_w), float(half_h), float(-z));
      gl_.ProgramUniform3f(program_, color_loc_, r, g, 0);
      gl_.DrawArrays(GL_TRIANGLES, 0, 6);
    };
    if (near_first) {
      plane(d, 0, 1);
      plane(d * (1 + gap), 1, 0);
    } else {
      plane(d * (1 + gap), 1, 0);
      plane(d, 0, 1);
    }
    std::vector<uint8_t> rgba(size_t(kW) * kH * 4);
    gl_.ReadPixels(0, 0, kW, kH, GL_RGBA, GL_UNSIGNED_BYTE, rgba.data());
    int wrong = 0;
    for (size_t p = 0; p < rgba.size(); p += 4) wrong += !(rgba[p] == 0 && rgba[p + 1] == 255);
    gl_.BindFramebuffer(GL_FRAMEBUFFER, 0);  // (the context rebinds its own on make_current)
    ctx_->make_current();
    return wrong;
  }

 private:
  std::unique_ptr<GlContext> ctx_;
  const GlApi& gl_;
  GLuint program_ = 0, vao_ = 0;
  GLint proj_loc_ = -1, min_loc_ = -1, max_loc_ = -1, color_loc_ = -1;
};

}  // namespace

TEST(HardDepth, ReverseZFloatDepthHasNoZFightingFromOneThousandthToOneMillion) {
  DepthPrecision dp;
  const Config configs[] = {
      {"conventional, 24-bit, GL_LESS", GL_DEPTH_COMPONENT24, false},
      {"conventional, float32, GL_LESS", GL_DEPTH_COMPONENT32F, false},
      {"reverse-Z, 24-bit, GL_GREATER", GL_DEPTH_COMPONENT24, true},
      {"reverse-Z, float32, GL_GREATER (used)", GL_DEPTH_COMPONENT32F, true},
  };
  const double distances[] = {0.01, 1, 10, 100, 1e3, 1e4, 1e5, 5e5};
  const int pixels = kW * kH;
  for (double gap : {1e-3, 1e-5}) {
    std::printf("[ figures  ] near %g far %g, planes at d and d*(1+%g): wrong pixels of %d (near drawn first / far drawn first)\n",
                kNear, kFar, gap, pixels);
    std::printf("[ figures  ] %-40s", "d =");
    for (double d : distances) std::printf(" %11g", d);
    std::printf("\n");
    for (const Config& cfg : configs) {
      std::printf("[ figures  ] %-40s", cfg.name);
      for (double d : distances) {
        const int a = dp.wrong_pixels(cfg, d, gap, true), b = dp.wrong_pixels(cfg, d, gap, false);
        std::printf(" %5d/%5d", a, b);
        if (cfg.reverse_z && cfg.depth_format == GL_DEPTH_COMPONENT32F) {
          EXPECT_EQ(a, 0) << cfg.name << " d=" << d << " gap=" << gap;
          EXPECT_EQ(b, 0) << cfg.name << " d=" << d << " gap=" << gap;
        }
      }
      std::printf("\n");
    }
  }
  // The conventional set-up does fail here (so the measurement can tell the two apart).
  EXPECT_GT(dp.wrong_pixels(configs[0], 1e4, 1e-3, false), pixels / 2);
}
