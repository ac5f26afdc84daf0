// Culling logic, independent of the renderer: hierarchical frustum culling and the HC traversal of the
// occlusion switch (paper Algorithm 4.1, breadth-first with a level of queries in flight at once,
// 4.7.1). The occlusion test itself sits behind OcclusionQueries: the occlusion back ends
// (occlusion_backend.hpp) test boxes against their depth; tests use CPU fakes.
#pragma once
#include <cstdint>
#include <functional>
#include <optional>
#include <span>
#include <vector>

#include "common/camera.hpp"
#include "common/cull/backend_choice.hpp"
#include "common/cull/enclosure.hpp"
#include "common/cull/query_skipper.hpp"
#include "common/scene/hierarchy.hpp"
#include "common/lod/lod_select.hpp"

namespace occ {

class OcclusionQueries {
 public:
  virtual ~OcclusionQueries() = default;
  // Starts an occlusion query for `box` against the current depth buffer; returns a handle.
  virtual uint32_t issue(const Aabb& box) = 0;
  // Samples of that box that passed the depth test (blocks until known).
  virtual uint64_t result(uint32_t handle) = 0;
  // Every result of the batch was read: handles may be recycled.
  virtual void end_batch() {}
  // Whether issue_cheap() can prove boxes occluded at a fraction of a test's cost (a depth
  // pyramid on the CPU or in one dispatch per batch): adaptive queries then still
  // test what they skip that way, so a leaf that became occluded leaves V at once instead of
  // after up to QuerySkipper::kMaxWait frames.
  virtual bool cheap_tests() const { return false; }
  // Only the cheap test for `box`: result() is 0 where it proves the box occluded, else 1 with
  // nothing tested further (assumed visible). Only where cheap_tests().
  virtual uint32_t issue_cheap(const Aabb& box) { return issue(box); }
  // Occluder fusion (HcChoices::occluder_fusion): the renderables the batch just read accepted,
  // before the next batch is issued. A tester that owns the depth it tests draws them (depth
  // only) into it, so what was just found visible hides what lies behind it in the same frame;
  // real geometry only adds depth that is really there, so the traversal stays conservative.
  // Default: nothing drawn.
  virtual void occluders_found(std::span<const uint32_t> renderables) { (void)renderables; }
  // Whether `leaf`, whose box test passed, may show by its own triangles (false: it is hidden and
  // culled, CullStats::geometry_hidden). Default: true (the box decides).
  virtual bool leaf_may_show(uint32_t leaf) {
    (void)leaf;
    return true;
  }
};

// Every box passes: with it HC's traversal returns the frustum set at the chosen LODs (a frame the
// render client's OcclusionGate sends without occlusion).
class FrustumOnlyQueries final : public OcclusionQueries {
 public:
  uint32_t issue(const Aabb&) override { return 0; }
  uint64_t result(uint32_t) override { return ~uint64_t(0); }
};

// True when a ray from the eye could enter `box` before reaching the near plane (the eye is in
// or on the box, or the box crosses the near plane close to the eye). A query would then
// rasterise only far faces or nothing and could report 0 samples although the content shows, so
// such boxes are visible without a query.
bool visible_without_query(const Aabb& box, const Camera& cam);

struct CullStats {
  uint32_t nodes_visited = 0;
  uint32_t frustum_culled = 0;     // nodes rejected by the frustum test
  uint32_t queries = 0;            // occlusion queries issued
  uint32_t occluded = 0;           // nodes whose query returned 0 samples
  uint32_t geometry_hidden = 0;    // leaves whose box passed and whose triangles did not (leaf_may_show)
  uint32_t near_visible = 0;       // nodes decided visible without a query
  uint32_t levels = 0;             // query batches (levels) issued
  uint32_t pixel_stops = 0;        // nodes accepted because fewer pixels than tau showed (4.7.2)
  uint32_t hlods = 0;              // interior nodes accepted at their HLOD
  uint32_t skipped = 0;            // queries skipped by a QuerySkipper (assumed visible)
  uint32_t skipped_occluded = 0;   // of the queries it skipped, proven occluded by a cheap test (in occluded)
  uint32_t sealed = 0;             // nodes hidden inside solids (Enclosures::hides), no query
};

// Leaves whose boxes are not outside the frustum, in ascending id order.
std::vector<uint32_t> frustum_cull(const Hierarchy& h, const Camera& cam, CullStats* stats = nullptr);

// What occlusion culling removed (render_client --window's O overlay): the non-empty leaves
// frustum_cull keeps for `cam` that neither are nor descend from any of `drawn_nodes` (the
// hierarchy nodes of a visible set: leaves, or interior nodes drawn at their HLOD). Ascending.
std::vector<uint32_t> occluded_leaves(const Hierarchy& h, const Camera& cam, std::span<const uint32_t> drawn_nodes);

// HardwareCull: breadth-first, one level at a time. For every node of a level: frustum test,
// then either visible_without_query() or an occlusion query; all queries of the level are issued
// before any result is read. Children of visible interior nodes form the next level; each
// visible leaf is reported through on_visible as soon as its level's results are in (streaming).
// Returns the visible leaves in ascending id order.
// `r`: the hierarchy's renderables, built once by a caller that culls every frame (its LOD data,
// if any, is not used). The Hierarchy overload builds them per call, for one-off culls.
std::vector<uint32_t> hardware_cull(const Renderables& r, const Camera& cam, OcclusionQueries& q,
                                    const std::function<void(uint32_t)>& on_visible,
                                    CullStats* stats = nullptr);
std::vector<uint32_t> hardware_cull(const Hierarchy& h, const Camera& cam, OcclusionQueries& q,
                                    const std::function<void(uint32_t)>& on_visible,
                                    CullStats* stats = nullptr);

// How LODs are chosen for one viewport: tau and the viewport height go together everywhere.
struct LodPolicy {
  double tau = 0;                  // pixels of error (0: original geometry only)
  double viewport_height_px = 1;
  bool visible_pixel_lod = false;  // accept a node whose query saw fewer than tau samples (4.7.2)
  LodSelector selector(const Renderables& r, const Camera& cam) const { return {r, cam, viewport_height_px, tau}; }
};

// How HC searches: the one option set, node-local (not in the config hash: the processes need not
// agree, the visible set stays a conservative superset either way). The CLI fills it
// (add_hc_options, protocol/cluster); the switch node's cull frame builds what each choice needs
// (switch_node/cull_frame.hpp); SwitchStep::hc and hardware_cull_lod read it through HcOptions.
struct HcChoices {
  // Adaptive queries and the visibility hold keep in V what a fresh test might drop (conservative),
  // to save tests; nullopt: the back end's default (choose_backend()).
  std::optional<bool> adaptive_queries = std::nullopt;  // assume nodes whose queries keep passing visible for a while (HcOptions::skipper)
  bool occluder_fusion = true;   // draw what each batch found visible before the next (OcclusionQueries::occluders_found)
  bool sealed = true;            // skip what is sealed inside solids (HcOptions::enclosures)
  std::optional<int> visibility_hold = std::nullopt;  // frames a node found visible stays in V (VisibilityHold; 0 off)
  // The occlusion back end (backend_choice.hpp; nullopt: auto, choose_backend()).
  std::optional<BackendKind> backend = std::nullopt;
};

// What the LOD traversal needs beyond the hierarchy, camera, queries and selector.
struct HcOptions {
  // Adaptive queries act through `skipper` (state the caller keeps across frames) and occluder
  // fusion through the queries (occluders_found), each only when its choice is on.
  HcChoices choices = {};
  bool visible_pixel_lod = false;
  std::span<const uint32_t> start = {};  // first batch: the fronts, occluded first; empty = the root
  QuerySkipper* skipper = nullptr;       // choices.adaptive_queries' state (null: query every node)
  const Enclosures* enclosures = nullptr;  // choices.sealed: nodes it hides for the camera are culled
  std::function<void(uint32_t)> on_visible = nullptr;  // each accepted renderable, as its batch resolves
  CullStats* stats = nullptr;
  // Bounds of a shell's size (hardware_cull_lod). Both at kWholeFrontier: every batch is the
  // whole frontier (from the root: one level of the hierarchy a batch, paper 4.7.1).
  uint32_t first_batch = 1, max_batch = 4096;
  static constexpr uint32_t kWholeFrontier = ~0u;
};

// HardwareCull with levels of detail (Algorithm 4.1 with 4.7.1 batching and 4.7.2). Like
// hardware_cull, but a visible node is accepted when sel.satisfies() it (interior: its HLOD meets
// tau; leaves always, at sel.leaf_level()), or, with visible_pixel_lod and tau > 0, when its query
// saw fewer than tau samples (then at its coarsest representation); other visible interior nodes
// are refined. The first batch is o.start. on_visible gets each accepted renderable id
// (lod_select.hpp) as its batch resolves. Returns the renderables, ascending. With tau = 0 it
// returns exactly hardware_cull's leaves.
std::vector<uint32_t> hardware_cull_lod(const Hierarchy& h, const Camera& cam, OcclusionQueries& q,
                                        const LodSelector& sel, const HcOptions& o = {});

// The items of the given nodes, ascending (the one draw order everywhere, so that z-ties resolve
// identically in every renderer).
std::vector<uint32_t> items_of_nodes(const Hierarchy& h, std::span<const uint32_t> nodes);

}  // namespace occ
