// One switch node's OR and HC for one render client (paper 3.2, 4.2-4.4): the node's visible set
// V, its occlusion back end (the OR's depth and HC's tests against it, occlusion_backend.hpp),
// and hardware culling (SwitchStep::hc with the node's HcChoices: adaptive queries, occluder
// fusion, the visibility hold), with what HC counted.
//
// The switch node's schedule (node.cpp) calls it frame by frame: begin_or(), take() for each
// message of the other node's stream of the previous frame, hc(). cull_overview replays two of
// them (one per node) in one process, so its picture is the cluster's by construction.
// Contracts: the back end's context (if any) is current on the calling thread; the back end and
// renderables outlive nothing they need. Create a fresh one per render client (nothing carries
// over).
#pragma once
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "common/cull/backend_choice.hpp"
#include "common/cull/culling.hpp"
#include "common/cull/depth_raster.hpp"
#include "common/cull/occlusion_backend.hpp"
#include "common/gl/context.hpp"
#include "common/gl/scene_renderer.hpp"
#include "protocol/cluster/cluster.hpp"
#include "protocol/cluster/switch_step.hpp"
#include "protocol/result.hpp"
#include "protocol/visible_set.hpp"

namespace occ {

// The process's back end, chosen once at start (choose_backend) from the context's renderer,
// `config`'s tau and visible-pixel LOD, whether the scene's triangles are in memory and hc's
// --backend; the choice's adaptive queries and visibility hold fill those left at auto.
BackendChoice choose_backend_for(const GlContext& ctx, const ClusterConfig& config, const HcChoices& hc,
                                 bool triangles_in_memory);
HcChoices with_backend_defaults(HcChoices hc, const BackendChoice& c);
// The back end of `c`. `cpu`: the scene's triangles on the CPU (required for BackendKind::cpu,
// outlives the back end); ctx, renderer, r outlive it too.
std::unique_ptr<OcclusionBackend> make_backend(const BackendChoice& c, GlContext& ctx, SceneRenderer& renderer,
                                               const Renderables& r, CpuOccluders* cpu, const ClusterConfig& config);

// Summed over the HC frames of one render client.
struct CullTotals {
  uint64_t frames = 0;              // HC frames
  uint64_t frustum_frames = 0;      // of those, sent as frustum sets (the render client's gate)
  uint64_t assumed_visible = 0;     // tests skipped by adaptive queries (CullStats::skipped)
  uint64_t skipped_occluded = 0;    // skipped ones the depth pyramid proved occluded (CullStats::skipped_occluded)
  uint64_t tests_above_fronts = 0;  // node tests front tracking saved (HcFrame::tests_above_fronts)
  uint64_t pixel_stops = 0, hlods = 0;
  uint64_t held = 0;                // renderables kept in V by the visibility hold
  uint64_t ors_after_frustum_sets = 0;  // ORs that left out V, a frustum set (begin_or)
};

class CullFrame {
 public:
  // `backend`: make_backend()'s; `choices`: with_backend_defaults()'s; `vp`: the cluster's
  // viewport; `other`: the other node's name, for the stream's errors; `sealed`: the scene's
  // items sealed inside solids (SceneGl::sealed).
  CullFrame(std::unique_ptr<OcclusionBackend> backend, const Renderables& r, const Enclosures& sealed,
            const ClusterConfig& config, const HcChoices& choices, Viewport vp, std::string other);
  CullFrame(const CullFrame&) = delete;
  CullFrame& operator=(const CullFrame&) = delete;

  const VisibleSet& visible() const { return visible_; }
  // A resync: V, the other node's stream, the visibility hold and the back end's memory start
  // from scratch.
  void restart();

  // OR(frame) for `cam`: clears depth and draws V depth only (V_{frame-2} in the switch,
  // V_{frame-1} alone). With occlusion false (a frustum-set frame) it draws nothing, and hc()
  // sends the frustum set. Where V is a frustum set (the first frames with occlusion after
  // frames without) and occluder fusion is on, V is not drawn: HC builds the depth nearest first
  // from what it finds visible, and a culled V from the other node's stream is drawn once that
  // stream is in.
  void begin_or(const Camera& cam, bool occlusion);

  // The other node's stream of frame `frame` (its HC), one message at a time: its camera (V is
  // coarsened for it), diff chunks (applied; additions drawn into the OR), its EndOfFrame (the
  // set and front hashes checked). Each take() says whether the stream is complete, or why the
  // other node broke it ("frame 7: sent two cameras", "desync: ...").
  enum class Stream { more, done };
  void begin_stream(uint32_t frame);
  Result<Stream> take(const wire::Message& m);

  // HC(frame) for `cam` on V_{frame-1} (the OR's depth): streams the diff to V_frame through
  // `out` and returns its EndOfFrame, not sent, without times. Its `queries` are the boxes the
  // back end tested in the frame (the summary's counts are the back end's, summed).
  HcFrame hc(uint32_t frame, const Camera& cam, DiffSender& out);

  const CullTotals& totals() const { return totals_; }
  const OcclusionBackend& backend() const { return *backend_; }

 private:
  void draw_v();  // what of V is not in the depth buffer yet, depth only
  void count(const HcFrame& hc);

  // The OR of this frame, from begin_or() to hc():
  //   off       the camera asks for no occlusion: nothing is drawn, hc() sends the frustum set;
  //   drawn     V was drawn, and the stream's additions are drawn as they come;
  //   deferred  V is a frustum set and occluder fusion is on: V is left out, and drawn at the
  //             stream's EndOfFrame where the other node's HC culled it (then: drawn).
  // begin_or() sets it; take() moves deferred to drawn; hc() ends the frame (off until the next
  // begin_or()).
  enum class OrState { off, drawn, deferred };
  // What V holds, once the stream's camera says how its frame was found (and after hc()).
  enum class VSource { culled, frustum_set };

  const std::unique_ptr<OcclusionBackend> backend_;
  const Renderables& r_;
  const Enclosures& sealed_;
  const ClusterConfig config_;
  const HcChoices choices_;
  const Viewport vp_;
  const std::string other_;
  const SwitchStep step_;
  std::optional<QuerySkipper> skipper_;
  std::optional<VisibilityHold> hold_;
  VisibleSet visible_;
  DiffReceiver stream_;  // the other node's HC frames
  OrState or_ = OrState::off;
  VSource v_ = VSource::culled;
  // The stream of one frame (begin_stream).
  struct Incoming {
    uint32_t frame = 0;
    bool have_camera = false;
    uint64_t expected_front = 0;
  } in_;
  CullTotals totals_;
};

}  // namespace occ
