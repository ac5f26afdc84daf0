// Occlusion queries on axis-aligned boxes against the current depth buffer (the GL side of
// HardwareCull, common/cull/culling.hpp). Each box is drawn as its front faces (12 triangles wound
// counter-clockwise from outside, back faces culled) with colour and depth writes off and the
// reverse-Z depth test GL_GREATER, inside a GL_SAMPLES_PASSED query (one pool
// per query target: a GL query object is tied to its first target, and this class only counts
// samples). Boxes are drawn camera-relative: min/max - eye in double, then float, enlarged by a
// relative epsilon (1e-5 of the corner's distance from the eye) and by at least kPadSubpixels
// sub-pixel steps on screen, so the result stays conservative: geometry lying on a box face
// still shows through it, and content whose edge the rasteriser snaps onto a pixel centre is
// still covered.
//
// Front faces suffice: with the eye outside the box they cover its whole silhouette and lie in
// front of its back faces, so a back-face fragment passes the depth test only where a front-face
// one does. A padded box within reach of the near rectangle (the eye inside it, or its front
// faces possibly clipped by the near plane) is not drawn and counts the viewport's pixels:
// the near plane may cut away its front faces where what the box holds lies beyond the plane,
// and its back faces lie behind that content (hard:walls, the eye 0.002 before a wall with the
// near plane at 0.001: the pad put the wall's flat box's front face before the plane, its back
// face behind the wall drawn as an occluder, and the wall was culled; docs/hard_cases.md).
//
// Batched use: begin(cam); issue() a whole level; result() each handle (the first waits for the
// GPU); reset() (or end_batch()) to recycle the handles; end() restores colour/depth writes.
// Contracts: the GlContext is current on the calling thread and outlives the querier.
#pragma once
#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "common/camera.hpp"
#include "common/cull/culling.hpp"
#include "common/gl/context.hpp"

namespace occ {

// The vertex shader drawing one box (uniforms u_view_projection, u_min, u_max) as 36 vertices
// from gl_VertexID, no attributes; also the culling overlay's (box_overlay.hpp).
extern const char* const kBoxVertexShader;

// A box program (BoxQuerier and BoxBatchCounter each link their own), its vertex array, and the
// state its boxes are drawn with from one camera (begin()).
struct BoxDrawState {
  GLuint program = 0, vao = 0;
  GLint view_projection_loc = -1;
  double subpixel_step = 0;  // the rasteriser's sub-pixel step in pixels
  glm::dvec3 eye{0.0};
  double reach = 0;      // eye to the near rectangle's corners, with slack
  double pixel_pad = 0;  // pad per unit of distance from the eye (BoxQuerier::kPadSubpixels)
  uint64_t pixels = 0;   // the viewport's: what a near box counts
  // Takes `linked_program` (it must have u_view_projection) and makes the vertex array.
  void create(const GlApi& gl, GLuint linked_program);
  void destroy(const GlApi& gl);
  // Sets the camera's uniforms and the query state (no colour or depth writes), binds the program.
  void begin(const GlApi& gl, const Camera& cam);
};

// What BoxQuerier and BoxBatchCounter share: their program's state, begin() and end(), and the
// count of boxes tested.
class BoxTester : public OcclusionQueries {
 public:
  BoxTester(const BoxTester&) = delete;
  BoxTester& operator=(const BoxTester&) = delete;
  // Sets up the state for tests from `cam` (does not clear the depth buffer).
  void begin(const Camera& cam) { box_.begin(gl_, cam); }
  // Restores colour and depth writes.
  void end();
  uint64_t queries_issued() const { return queries_issued_; }  // boxes tested, since construction

 protected:
  BoxTester(GlContext& ctx, GLuint linked_program);  // takes the program (BoxDrawState::create)
  ~BoxTester() override;
  const GlApi& gl_;
  BoxDrawState box_;
  uint64_t queries_issued_ = 0;
};

class BoxQuerier final : public BoxTester {
 public:
  static constexpr double kRelativePad = 1e-5;
  // Boxes are also enlarged on screen by at least this many steps of the rasteriser's sub-pixel
  // grid (GL_SUBPIXEL_BITS): vertices are snapped to it (half a step each way) and ties on pixel
  // centres are broken by edge rules, so content seen edge-on can cover a pixel its exact box
  // only grazes. 4 steps: 1/64 px on llvmpipe (8 bits).
  static constexpr double kPadSubpixels = 4;

  explicit BoxQuerier(GlContext& ctx);
  ~BoxQuerier() override;

  // Starts a query for `box`, draws it, ends the query. An empty box draws nothing (0 samples).
  uint32_t issue(const Aabb& box) override;
  // Samples that passed the depth test for a handle of the current batch (waits for it).
  // Throws std::out_of_range for a handle not issued since the last reset().
  uint64_t result(uint32_t handle) override;
  // True when the handle's result can be read without waiting.
  bool ready(uint32_t handle) const;
  // Recycles every handle of the batch (their results are no longer needed).
  void reset();
  void end_batch() override { reset(); }

 private:
  GLint min_loc_ = -1, max_loc_ = -1;
  std::vector<GLuint> pool_;  // GL_SAMPLES_PASSED query objects
  std::vector<uint8_t> near_; // per handle of the batch: a near box (not drawn: the viewport's pixels)
  uint32_t next_ = 0;         // first unused query of the pool in this batch
};

// The same test for a whole batch in one draw ("tighter batching"): issue() records the
// box; the first result() draws every recorded box in one draw call (boxes within reach of the
// near rectangle not: they count as BoxQuerier's) from a buffer, with a fragment shader that
// runs only for fragments passing the depth test (early fragment tests) and counts them in its
// box's counter in a shader storage buffer; the counters are read back once. Same boxes, same
// triangles, same depth test as BoxQuerier (a single-sampled framebuffer; depth writes off, so
// boxes of a batch do not hide each other): with `exact`, each count equals GL_SAMPLES_PASSED of
// that box's query; without, it is 1 where that is > 0 (and 0 where it is 0) - enough for HC
// unless it needs sample counts (visible-pixel LOD). No query objects: llvmpipe bins the begin and
// the end of every query into every tile of the framebuffer, at 1024 x 1024 a large part of a
// query's cost.
class BoxBatchCounter final : public BoxTester {
 public:
  BoxBatchCounter(GlContext& ctx, bool exact);
  bool exact() const { return exact_; }
  ~BoxBatchCounter() override;

  uint32_t issue(const Aabb& box) override;
  uint64_t result(uint32_t handle) override;
  void reset();
  void end_batch() override { reset(); }
  uint64_t draws() const { return draws_; }                    // batches drawn
  // Draws the batch (the first result() does it); its counts are then read back.
  void draw();
  bool drawn() const { return drawn_; }

 private:
  bool exact_;
  GLuint boxes_buf_ = 0, counts_buf_ = 0;
  GLint first_loc_ = -1;
  size_t capacity_ = 0;
  std::vector<Aabb> boxes_;
  std::vector<uint32_t> slot_;
  std::vector<uint64_t> counts_;
  bool drawn_ = false;
  uint64_t draws_ = 0;
};

}  // namespace occ
