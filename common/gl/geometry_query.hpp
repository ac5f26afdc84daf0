// Geometry queries for leaves (HcOptions::leaf_test == LeafTest::geometry, common/culling.hpp):
// wraps the box queries of HC (any OcclusionQueries: BoxQuerier) and adds issue_geometry(), a
// GL_SAMPLES_PASSED query around the renderable's own depth-only geometry
// (SceneRenderer::query_renderables: the OR's programs, vertices, face culling and alpha test,
// depth test GL_GEQUAL, no writes). Box queries go straight to the wrapped querier; geometry
// queries are collected and drawn in one batched call at the first geometry result() of the
// batch (one upload of records and commands for all of them), after which `restore` puts back
// the state the box queries need (BoxQuerier::begin). A renderable holding BLEND items is not
// tested (kNoGeometryQuery): depth-only draws leave BLEND out although it shows in the frame.
//
// Handles: the wrapped querier's below kGeometryBit, geometry queries kGeometryBit | index.
// Contracts: as BoxQuerier (the GlContext current on the calling thread, outliving this); the
// wrapped querier, renderer and renderables outlive this; the depth buffer is the one the box
// queries test.
#pragma once
#include <cstdint>
#include <functional>
#include <vector>

#include <stdexcept>

#include "common/culling.hpp"
#include "common/gl/context.hpp"
#include "common/gl/scene_renderer.hpp"
#include "common/lod.hpp"

namespace occ {

class GeometryQuerier final : public OcclusionQueries {
 public:
  // Marks this querier's geometry handles. Bit 30: the wrapped box querier's handles are batch
  // indices, possibly with bit 31 set (HcQuerier marks its real queries so), never bit 30.
  static constexpr uint32_t kGeometryBit = 0x40000000u;

  GeometryQuerier(GlContext& ctx, OcclusionQueries& boxes, SceneRenderer& renderer, const Renderables& r,
                  std::function<void()> restore);
  ~GeometryQuerier() override;
  GeometryQuerier(const GeometryQuerier&) = delete;
  GeometryQuerier& operator=(const GeometryQuerier&) = delete;

  uint32_t issue(const Aabb& box) override {
    const uint32_t h = boxes_.issue(box);
    if (h & kGeometryBit) throw std::logic_error("GeometryQuerier: a box handle uses the geometry bit");
    return h;
  }
  // Box handles: the wrapped querier's result. Geometry handles: draws the batch's geometry
  // queries first if they are not drawn yet. Throws std::out_of_range for a geometry handle not
  // issued in this batch.
  uint64_t result(uint32_t handle) override;
  void end_batch() override;
  bool geometry_queries() const override { return true; }
  uint32_t issue_geometry(uint32_t renderable) override;

  uint64_t geometry_queries_issued() const { return issued_; }  // since construction

 private:
  void flush();

  const GlApi& gl_;
  OcclusionQueries& boxes_;
  SceneRenderer& renderer_;
  const Renderables& r_;
  std::function<void()> restore_;
  std::vector<GLuint> pool_;       // GL_SAMPLES_PASSED query objects
  std::vector<uint32_t> ids_;      // this batch's renderables, by handle index
  size_t drawn_ = 0;               // ids_[0, drawn_) are drawn
  uint64_t issued_ = 0;
};

}  // namespace occ
