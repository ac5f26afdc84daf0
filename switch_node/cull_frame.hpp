// One switch node's OR and HC for one render client (paper 3.2, 4.2-4.4): the node's visible set
// V, the occlusion representation (V and the other node's streamed additions, drawn depth only)
// and hardware culling against it (SwitchStep::hc with the node's HcChoices: the HcQuerier,
// adaptive queries, occluder fusion, the visibility hold), with what HC counted.
//
// The switch node's schedule (node.cpp) calls it frame by frame: begin_or(), take() for each
// message of the other node's stream of the previous frame, hc(). cull_overview replays two of
// them (one per node) in one process, so its picture is the cluster's by construction.
// Contracts: the GL context is current on the calling thread; the context, renderer and
// renderables outlive this; the renderer draws depth only for this (its occluder offset is set). Create a fresh one per render client (nothing carries over).
#pragma once
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "common/cull/culling.hpp"
#include "common/cull/depth_raster.hpp"
#include "common/cull/raster_queries.hpp"
#include "common/gl/context.hpp"
#include "common/gl/hzb_query.hpp"
#include "common/gl/scene_renderer.hpp"
#include "protocol/cluster/cluster.hpp"
#include "protocol/cluster/switch_step.hpp"
#include "protocol/result.hpp"
#include "protocol/visible_set.hpp"

namespace occ {

// Whether HC tests on the CPU (RasterQueries, no GL in the frame): the OR there (or_on_cpu), tau 0
// and --hc-test auto (a --hc-test given tests in GL against the OR's depth uploaded).
bool hc_tests_on_cpu(bool or_on_cpu, const ClusterConfig& config, const HcChoices& choices);

// Summed over the HC frames of one render client.
struct CullTotals {
  uint64_t frames = 0;              // HC frames
  uint64_t frustum_frames = 0;      // of those, sent as frustum sets (the render client's gate)
  uint64_t queries = 0;             // occlusion queries (CullStats::queries)
  uint64_t assumed_visible = 0;     // queries skipped by adaptive queries (CullStats::skipped)
  uint64_t skipped_occluded = 0;    // skipped ones the depth pyramid proved occluded (CullStats::skipped_occluded)
  uint64_t tests_above_fronts = 0;  // node tests front tracking saved (HcFrame::tests_above_fronts)
  uint64_t pixel_stops = 0, hlods = 0;
  uint64_t held = 0;                // renderables kept in V by the visibility hold
  uint64_t ors_after_frustum_sets = 0;  // ORs that left out V, a frustum set (begin_or)
  uint64_t geometry_hidden = 0;     // leaves whose box showed and whose triangles did not (the OR on the CPU)
};

class CullFrame {
 public:
  // `vp`: the cluster's viewport; `other`: the other node's name, for the stream's errors;
  // `sealed`: the scene's items sealed inside solids (SceneGl::sealed). `cpu`: the OR draws V on
  // the CPU into it (SceneGl::cpu_occluders; null: in GL), and HC starts from that depth.
  CullFrame(GlContext& ctx, SceneRenderer& renderer, const Renderables& r, const Enclosures& sealed,
            const ClusterConfig& config, const HcChoices& choices, Viewport vp, std::string other,
            CpuOccluders* cpu = nullptr);
  CullFrame(const CullFrame&) = delete;
  CullFrame& operator=(const CullFrame&) = delete;

  const VisibleSet& visible() const { return visible_; }
  // A resync: V, the other node's stream and the visibility hold start from scratch.
  void restart();

  // OR(frame) for `cam`: clears depth and draws V depth only (V_{frame-2} in the switch,
  // V_{frame-1} alone). With occlusion false (a frustum-set frame) it draws nothing, and hc()
  // sends the frustum set. Where V is a frustum set (the first frames with occlusion after
  // frames without: drawing it cost the OR a whole frustum render, depth only) and occluder
  // fusion is on, V is not drawn: HC builds the depth nearest first from what it finds visible,
  // and a culled V from the other node's stream is drawn once that stream is in.
  void begin_or(const Camera& cam, bool occlusion);

  // The other node's stream of frame `frame` (its HC), one message at a time: its camera (V is
  // coarsened for it), diff chunks (applied; additions drawn into the OR), its EndOfFrame (the
  // set and front hashes checked). Each take() says whether the stream is complete, or why the
  // other node broke it ("frame 7: sent two cameras", "desync: ...").
  enum class Stream { more, done };
  void begin_stream(uint32_t frame);
  Result<Stream> take(const wire::Message& m);

  // HC(frame) for `cam` on V_{frame-1} (the OR's depth): streams the diff to V_frame through
  // `out` and returns its EndOfFrame, not sent, without times.
  HcFrame hc(uint32_t frame, const Camera& cam, DiffSender& out);

  const CullTotals& totals() const { return totals_; }
  const HcQuerier& querier() const { return querier_; }
  bool hc_on_cpu() const;  // hc_tests_on_cpu() for this frame's OR
  // HC's tests on the CPU (hc_on_cpu()); null otherwise.
  const RasterQueries* raster_queries() const { return raster_queries_ ? &*raster_queries_ : nullptr; }

 private:
  void draw_v();  // what of V is not in the depth buffer yet, depth only
  std::vector<uint32_t> draw_new_occluders(std::span<const uint32_t> ids);
  void draw_depth(std::span<const uint32_t> ids);  // the OR's draw: on the CPU while or_on_cpu_, else GL
  void count(const HcFrame& hc);

  GlContext& ctx_;
  SceneRenderer& renderer_;
  const Renderables& r_;
  const Enclosures& sealed_;
  const ClusterConfig config_;
  const HcChoices choices_;
  const Viewport vp_;
  const std::string other_;
  const SwitchStep step_;
  HcQuerier querier_;
  std::optional<QuerySkipper> skipper_;
  std::optional<VisibilityHold> hold_;
  VisibleSet visible_;
  DiffReceiver stream_;          // the other node's HC frames
  std::vector<uint8_t> drawn_;   // renderables in this frame's depth buffer
  bool occlusion_ = true;        // this frame's camera asks for occlusion
  bool v_frustum_set_ = false;   // V is a frustum set (its frame was culled without occlusion)
  bool or_deferred_ = false;     // this OR left V out (a frustum set) until the stream is in
  CpuOccluders* cpu_ = nullptr;  // the OR on the CPU (null: GL)
  std::optional<RasterQueries> raster_queries_;  // with cpu_: HC's box tests at tau 0
  bool or_on_cpu_ = false;       // between begin_or() and hc(): the OR's draws go to cpu_
  bool cpu_drawn_ = false;       // cpu_ holds something this frame (uploaded at hc())
  static constexpr uint32_t kGeometryRecheck = 16;
  std::vector<uint32_t> geometry_seen_;  // per node: the last frame its triangles showed (0: none)
  // The stream of one frame (begin_stream).
  struct Incoming {
    uint32_t frame = 0;
    bool have_camera = false, started = false;
    uint64_t expected_front = 0;
    std::vector<uint32_t> before;  // full sets with a hold: V' (sorted)
  } in_;
  CullTotals totals_;
};

}  // namespace occ
