// A depth buffer rasterised on the CPU, for the OR where GL itself runs on the CPU (llvmpipe):
// depth only, no shading, so a triangle costs its setup and the pixels it covers, without
// llvmpipe's vertex pipeline, binning and JIT fragment calls.
//
// Conservative against GL's own depth of the same triangles, so that what HC proves hidden
// behind it is hidden in every GL frame: each pixel holds at most (in reverse-Z: no nearer than)
// what GL would write there. Three things make it so:
//   - depth: computed in double, each triangle's plane moved back by twice the GL occluder
//     offset (SceneRenderer::kOccluderSlopeOffset of its largest depth slope per pixel) and by
//     more than GL's float arithmetic may err (its depth is P22 z + P32 over w, whose terms
//     nearly cancel far off, and a plane set up from corners far off screen);
//   - coverage: pixel centres, edges snapped to 1/256 pixel with a top-left rule; GL's own
//     snapping may put an edge on the other side of a centre within rounding of it (2/256
//     pixel, more far off screen), so such centres are left out, except along an edge whose
//     triangle across (same mesh, same draw) lies on its other side on screen: there one of
//     the two covers the centre in either rasteriser (and leaving them out would open cracks);
//   - what is hard to match is left out (leaving out occluders only makes HC prove less): parts
//     of a triangle in front of the near plane are clipped away, and so are parts more than
//     2^17 pixels off screen (a guard band: the edges of what is left keep their place).
// It also tests triangles against what it holds (shows()), conservatively the other way.
// Depth convention as common/cull/hzb.hpp: reverse-Z, 1 = near plane, 0 = far / cleared; rows
// bottom first (GL order).
#pragma once
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "common/camera.hpp"
#include "common/scene/hierarchy.hpp"
#include "common/scene/scene.hpp"

namespace occ {

class DepthRaster {
 public:
  DepthRaster(int width, int height);
  int width() const { return width_; }
  int height() const { return height_; }

  void clear();  // every pixel far (0)
  // The projection's depth terms (P[2][2] and P[3][2]: clip z = P22 z_eye + P32): GL's rounding
  // of them bounds how far its depth may be from the exact one, which draws and tests allow for.
  void set_projection(double p22, double p32);

  // Which faces are drawn: both, or the front ones only (counter-clockwise on screen, or
  // clockwise: a mirroring transform), as GL's face culling.
  enum class Faces { both, ccw, cw };
  // Draws triangles `indices` (whole triangles) of `positions`, mapped to clip space by
  // `clip_from_object` (projection * view * model, reverse-Z, depth range 0..1). `across`
  // (adjacency(), for these indices, or empty): edges shared with a triangle drawn in the same
  // call need no margin where that triangle lies on the other side on screen.
  void draw(const glm::dmat4& clip_from_object, std::span<const glm::vec3> positions,
            std::span<const uint32_t> indices, Faces faces, std::span<const uint32_t> across = {});

  // For each corner of `indices` (whole triangles), the edge from it to the next corner: the
  // vertex across it of the one other triangle sharing it (corners welded by position), with
  // kReversed where that triangle runs the edge the other way (consistent winding); kNone where
  // not exactly two triangles share it.
  static constexpr uint32_t kNone = 0xffffffffu, kReversed = 0x80000000u;
  static std::vector<uint32_t> adjacency(std::span<const glm::vec3> positions, std::span<const uint32_t> indices);

  // Whether any of these triangles shows in front of the depth drawn so far: conservative the
  // other way (a centre GL may cover counts, at the plane moved forward by what draw() moves it
  // back), so that triangles found not to show are hidden in every GL frame drawn over that
  // depth. Not drawn.
  bool shows(const glm::dmat4& clip_from_object, std::span<const glm::vec3> positions,
             std::span<const uint32_t> indices, Faces faces, std::span<const uint32_t> across = {});

  // As shows(), for the faces of a query box (counter-clockwise seen from outside: its front
  // faces are tested, clipped at the near plane): whether GL's occlusion query of
  // those faces over GL's depth of the occluders drawn here could count a sample. The planes are
  // moved forward by GL's float rounding only, not by the OR's occluder offset: the occluders
  // drawn here already lie behind GL's by that offset, as GL's OR draws them for its queries.
  bool query_shows(const glm::dmat4& clip_from_object, std::span<const glm::vec3> positions,
                   std::span<const uint32_t> indices);

  // The depth drawn so far (width() x height(), row 0 at the bottom).
  std::span<const float> depth() const { return depth_; }


 private:
  struct V {  // a vertex after projection: window position (pixels), depth and clip w
    double x, y, z, w;
  };
  struct Setup;
  bool run(const glm::dmat4& clip_from_object, std::span<const glm::vec3> positions,
           std::span<const uint32_t> indices, Faces faces, bool test, std::span<const uint32_t> across);
  // `outline`: bit k set where edge k (corner k to k + 1) needs the margin (uncertain pixels).
  bool setup(const V& a, const V& b, const V& c, Faces faces, bool test, uint8_t outline, Setup& s) const;
  static void span(const Setup& s, const int64_t* E, const int64_t* above, int64_t& lo, int64_t& hi);
  void triangle(const V& a, const V& b, const V& c, Faces faces, uint8_t outline);
  bool test_triangle(const V& a, const V& b, const V& c, Faces faces, uint8_t outline) const;
  bool clip_and_draw(const glm::dvec4& a, const glm::dvec4& b, const glm::dvec4& c, Faces faces, bool test,
                     uint8_t outline);
  V project(const glm::dvec4& p) const;

  int width_, height_;
  std::vector<float> depth_;
  std::vector<glm::dvec4> clip_;     // the draw's vertices in clip space
  std::vector<V> window_;            // and projected (those not in front of the near plane)
  std::vector<uint32_t> stamp_;      // clip_[v] is current when stamp_[v] == draw_
  uint32_t draw_ = 0;
  double error_ = 0, error_w_ = 0;   // GL's depth error: error_ + error_w_ / w (set_projection)
  bool as_query_ = false;            // query_shows() in progress
};

// The OR's occluders on the CPU: the opaque items' triangles (full detail), copied from the scene
// before the GL upload releases its arrays, drawn into a DepthRaster by renderable.
class CpuOccluders {
 public:
  // Nullopt, and `why`, where the scene's arrays are not in memory (read lazily from the scene
  // cache: the scene is larger than the geometry budget) or already released.
  static std::optional<CpuOccluders> copy(const Scene& scene, const Hierarchy& h, int width, int height,
                                          std::string* why);

  void begin(const Camera& cam);  // clears the depth; the frame's camera
  // Draws the items of leaf `node` at full detail (level 0). Other renderables (a leaf's coarser
  // level, an interior node's HLOD: not on the CPU), MASK or BLEND items and items a section
  // plane of the camera cuts are left out.
  void draw_leaf(uint32_t node, uint32_t level);
  // Whether leaf `node` at full detail may show in front of the depth drawn so far
  // (DepthRaster::shows): false only where every item is opaque and none of its triangles shows.
  bool leaf_shows(uint32_t node);
  // Whether content inside `box` (world) may show in front of the depth drawn so far: its faces
  // (the box padded by relative_pad of its farthest camera-relative coordinate, as GL's query
  // box) tested as GL's query of them would be (DepthRaster::query_shows); the padded box within
  // reach of the near rectangle shows, as GL's query counts it (common/gl/box_query.hpp).
  bool box_shows(const Aabb& box, double relative_pad);
  DepthRaster& raster() { return raster_; }
  uint64_t bytes() const;  // the copies' memory

 private:
  CpuOccluders(const Hierarchy& h, int width, int height) : h_(&h), raster_(width, height) {}
  struct MeshCopy {
    std::vector<glm::vec3> positions;
    std::vector<uint32_t> indices;
    std::vector<uint32_t> across;  // DepthRaster::adjacency within each item's cluster
  };
  struct ItemRef {
    uint32_t mesh = 0, first_index = 0, index_count = 0;
    DepthRaster::Faces faces = DepthRaster::Faces::both;
    bool occludes = false;  // opaque
    glm::dmat4 transform{1.0};
  };
  const Hierarchy* h_;
  std::vector<MeshCopy> meshes_;
  std::vector<ItemRef> items_;
  glm::dmat4 clip_from_world_{1.0};
  glm::dvec3 eye_{0.0};
  Sections sections_;  // the frame camera's
  double pixel_per_distance_ = 0;  // a pixel's height at unit distance from the eye
  double near_reach_ = 0;          // the eye to the near rectangle's corners, with slack
  DepthRaster raster_;
};

// DepthRaster's spans (inner loops), exposed so a test holds the vector versions (AVX2, where
// the CPU has it) to the scalar ones: pixel k of n at the plane's z0 + dz k, in double, rounded
// to float. fill(): each kept where greater than row[k] (at most 1); reaches(): whether any is at
// or in front of row[k]. `vector` false: the scalar loop.
namespace depth_span {
bool vector_available();
void fill(float* row, int64_t n, double z0, double dz, bool vector = true);
bool reaches(const float* row, int64_t n, double z0, double dz, bool vector = true);
}  // namespace depth_span

}  // namespace occ
