// Culling logic, independent of GL: hierarchical frustum culling and the HC traversal of the
// occlusion switch (paper Algorithm 4.1, breadth-first with a level of queries in flight at once,
// 4.7.1). The occlusion test itself sits behind OcclusionQueries: the GL implementation renders
// boxes (and, optionally, a leaf's own geometry) against the depth buffer; tests use a CPU fake.
#pragma once
#include <cstdint>
#include <functional>
#include <span>
#include <vector>

#include "common/camera.hpp"
#include "common/hierarchy.hpp"
#include "common/lod_select.hpp"

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

  // Geometry queries (HcOptions::leaf_test == LeafTest::geometry): a leaf whose box query passed
  // is tested again with its own geometry, the renderable exactly as the OR draws it depth only
  // (same vertices, programs, face culling and alpha test), with the depth test GL_GEQUAL
  // (reverse-Z: ties pass) and no depth writes. Its handle's result() is the samples that passed.
  // Implementations without them return false here (the traversal then keeps box results).
  virtual bool geometry_queries() const { return false; }
  static constexpr uint32_t kNoGeometryQuery = ~uint32_t(0);
  // Starts a geometry query for renderable `renderable` (lod_select.hpp ids) in the current
  // batch; kNoGeometryQuery when it cannot be tested (it holds BLEND items, which depth-only
  // draws leave out although they show): the caller then keeps the box's answer.
  virtual uint32_t issue_geometry(uint32_t /*renderable*/) { return kNoGeometryQuery; }
};

// Every box passes: with it HC's traversal returns the frustum set at the chosen LODs (a frame the
// render client's OcclusionGate sends without occlusion). No GL.
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

// The pixels `box` covers on screen (the area of the convex hull of its projected corners, not
// clipped to the viewport); +inf when a corner lies at or behind the plane of the eye.
double projected_box_area_px(const Aabb& box, const Camera& cam, double viewport_height_px);

struct CullStats {
  uint32_t nodes_visited = 0;
  uint32_t frustum_culled = 0;     // nodes rejected by the frustum test
  uint32_t queries = 0;            // occlusion queries issued
  uint32_t occluded = 0;           // nodes whose query returned 0 samples
  uint32_t near_visible = 0;       // nodes decided visible without a query
  uint32_t levels = 0;             // query batches (levels) issued
  uint32_t pixel_stops = 0;        // nodes accepted because fewer pixels than tau showed (4.7.2)
  uint32_t hlods = 0;              // interior nodes accepted at their HLOD
  uint32_t skipped = 0;            // queries skipped by a QuerySkipper (assumed visible)
  uint32_t whole = 0;              // subtrees accepted whole by a QueryBudget (no queries)
  uint32_t geometry_queries = 0;   // leaves whose box passed, tested with their geometry
  uint32_t geometry_occluded = 0;  // of those, leaves whose geometry showed no sample (rejected)
};

// Pays for occlusion queries only where they cull (the cost/benefit idea of the OpenGL-assisted
// culling paper): a node whose query came back visible kTrust times in a row is assumed visible,
// without a query, for its next `wait` visits; every confirmation doubles the wait (up to
// kMaxWait), an occluded result resets it. Assuming visible is conservative: the node is accepted
// or descended exactly as if its query had passed, so no frame changes; only the visible set may
// keep a node for up to kMaxWait visits after it became occluded. A scene with little occlusion
// (an open field, the outside of one object) thus stops paying for queries that never cull.
class QuerySkipper {
 public:
  // 2 and 32 (were 3 and 16): duplex orbit at 1024^2, HC CPU -15 to -20 %; c45walk at 512^2 tau 0,
  // p99 frame interval 11.1-12.7 against 12.9-18.6 ms; PVS/exact +0.01-0.04 (docs/spikes.md).
  static constexpr uint8_t kTrust = 2;
  static constexpr uint8_t kMaxWait = 32;
  // A leaf with more triangles than this is queried every time: skipping its query saves one
  // box test, but if it has become occluded it is drawn for nothing, twice (the other node's
  // OR and the render client), for up to kMaxWait frames. Duplex orbit at 512^2 (the cluster,
  // paired runs): triangles sent 13.5 k -> 7.2 k per frame for +1 % queries, frame interval
  // -7 %; 50 and 100 query more for less; the city and the saw unchanged (docs/results.md).
  static constexpr uint64_t kMaxSkippedLeafTriangles = 150;
  // Whether `n`'s query may be skipped at all (interior nodes: their children are tested).
  static bool may_skip(const HNode& n) { return !n.leaf() || n.triangles <= kMaxSkippedLeafTriangles; }
  explicit QuerySkipper(size_t nodes) : state_(nodes) {}
  // True when `node` is assumed visible this time (consumes one visit of its wait).
  bool skip(uint32_t node);
  void record(uint32_t node, bool visible);

 private:
  struct State {
    uint8_t streak = 0, wait = 0, remaining = 0;
  };
  std::vector<State> state_;
};

// Occlusion only where it pays (cost model): for every subtree, what its queries cost the last
// time HC tested it (queries issued x measured time per query) against what they saved (the
// triangles they found occluded x measured time to draw a triangle, in OR and RVG). A visible
// interior node whose subtree's queries cost more than they saved is accepted whole — every
// non-empty leaf of it in the frustum, without queries (interior nodes at their HLOD where the
// selector allows) — for its next `wait` visits (4, doubling up to 32), then tested again to
// refresh the figures. Accepting more than is visible is conservative: frames never change, only
// what is drawn. Until costs are set (set_costs) every subtree is tested.
class QueryBudget {
 public:
  static constexpr uint8_t kFirstWait = 4, kMaxWait = 32;
  explicit QueryBudget(const Hierarchy& h);
  void set_costs(double ms_per_query, double ms_per_triangle);
  // True when the visible interior `node` is to be accepted whole this visit (consumes a visit).
  bool accept_whole(uint32_t node);
  // The traversal reports what it tested; end_traversal() folds it into per-subtree figures.
  void visited(uint32_t node) { touched_.push_back(node); }
  void queried(uint32_t node, bool visible);
  void end_traversal();
  // Figures of the last test of `node`'s subtree (for tests and logs).
  uint32_t subtree_queries(uint32_t node) const { return state_.at(node).queries; }
  uint64_t subtree_saved_triangles(uint32_t node) const { return state_.at(node).saved; }

 private:
  struct State {
    uint32_t queries = 0;  // last test: queries in the subtree
    uint64_t saved = 0;    // last test: triangles found occluded in the subtree
    uint8_t wait = 0, remaining = 0;
    bool probe = false;      // the wait is over: test the subtree once to refresh the figures
    bool whole_now = false;  // accepted whole in this traversal (its figures stay)
    uint32_t q_now = 0;    // this traversal (folded by end_traversal)
    uint64_t s_now = 0;
    int8_t result = -1;    // this traversal: -1 not queried, 0 occluded, 1 visible
  };
  const Hierarchy& h_;
  std::vector<State> state_;
  std::vector<uint32_t> touched_;
  double ms_per_query_ = 0, ms_per_triangle_ = 0;
};

// Hysteresis for the visible set (issue 15): a node HC found visible (in two frames, see recent())
// stays in V for up to `frames` frames after the last frame it was seen, while it stays in the
// frustum. Leaves that
// flicker in and out of V between frames (a query that passes in one node's depth buffer and not
// in the other's, a leaf seen through a gap every other frame) then cost no ids on the wire and
// no re-draws at the edges of their visibility. Keeping more than is visible is conservative:
// frames never change. Node-local state: each switch node records what its own HC found and the
// additions it receives from the other node (an added id was found visible); what it cannot
// know (the other node's kept ids) only shortens the hold.
class VisibilityHold {
 public:
  VisibilityHold(size_t nodes, uint32_t frames) : frames_(frames), last_(nodes, 0), prev_(nodes, 0) {}
  uint32_t frames() const { return frames_; }
  // `node` was found visible in `frame`.
  void seen(uint32_t node, uint32_t frame) {
    if (frame + 1 <= last_.at(node)) return;
    prev_[node] = last_[node];
    last_[node] = frame + 1;
  }
  // Seen in one of the `frames` frames before `frame` (or in it), and once more before that within
  // 4 x `frames` frames. A node seen in one frame only is not held: a set that exploded for one
  // frame (start-up, the eye leaving a closed room) is not carried into the next frames.
  bool recent(uint32_t node, uint32_t frame) const {
    const uint32_t l = last_.at(node), p = prev_[node];
    return l != 0 && l - 1 + frames_ >= frame && p != 0 && p - 1 + 4 * frames_ >= frame;
  }
  // The renderables of `prev` (V_{f-1}, front-tracking coarsened) to keep in V_f beside `found`
  // (HC's result, ascending): recently seen, box not outside the frustum, and neither the same
  // node as, an ancestor of, nor a descendant of a node in `found` (V_f stays an antichain: one
  // representation per part of the scene). Ascending.
  std::vector<uint32_t> held(const Renderables& r, const Camera& cam, std::span<const uint32_t> prev,
                             std::span<const uint32_t> found, uint32_t frame) const;

 private:
  uint32_t frames_;
  std::vector<uint32_t> last_, prev_;  // per node: last / previous frame seen + 1 (0: never)
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

// The order in which the traversal batches its queries.
enum class HcOrder {
  levels,      // breadth-first: a whole level of the hierarchy per batch (paper 4.7.1)
  near_first,  // nearest boxes first: shells from a distance-ordered queue (the nearest box at d
               // and all within 2d), so the near occluders found (and drawn, HcOptions::occluders)
               // hide what the next shell holds
};

// How a leaf whose box query passed is decided.
enum class LeafTest {
  box,       // accepted on its box
  geometry,  // tested again with its own geometry (OcclusionQueries::issue_geometry): accepted
             // only if samples pass. Conservative, and exact at tau 0: the depth buffer holds
             // real geometry only, pushed back by the OR's polygon offset, so every pixel where
             // the leaf is the nearest surface passes. HLODs keep box queries; leaves decided
             // without a query (near, skipped, held, accepted whole) are accepted as before.
};
// How HC tests a box (common/gl/hzb_query.hpp HcQuerier): an occlusion query each; a GPU depth
// pyramid first with queries for the boxes it cannot prove occluded (every batch, or where it pays:
// automatic); or a whole batch in one draw counting samples in a buffer (batch). The answers are
// the same: only what they cost differs.
enum class HcTest { queries, pyramid, automatic, batch, cpu_pyramid };

// What the LOD traversal needs beyond the hierarchy, camera, queries and selector.
struct HcOptions {
  bool visible_pixel_lod = false;
  std::span<const uint32_t> start = {};  // first batch: the fronts, occluded first; empty = the root
  QuerySkipper* skipper = nullptr;       // adaptive queries (null: query every node)
  QueryBudget* budget = nullptr;         // accept subtrees whole where queries do not pay
  std::function<void(uint32_t)> on_visible = nullptr;  // each accepted renderable, as its batch resolves
  CullStats* stats = nullptr;
  HcOrder order = HcOrder::levels;
  uint32_t first_batch = 1, max_batch = 4096;  // near_first: bounds of a shell's size
  // Occluder fusion: called after each batch with the renderables it accepted, before the next
  // batch is issued; the caller draws them (depth only) into the buffer the queries test, so what
  // was just found visible hides what lies behind it in the same frame. Real geometry only adds
  // depth that is really there: the traversal stays conservative.
  std::function<void(std::span<const uint32_t>)> occluders = nullptr;
  // geometry: a batch's geometry queries are issued after its box results are read (one more
  // wait per batch), when q.geometry_queries(). The skipper and the budget learn the final
  // answer (box and geometry), so a leaf hidden behind its box's window is not trusted.
  LeafTest leaf_test = LeafTest::box;
  // geometry: only leaves whose box query saw fewer samples than this fraction of the box's
  // projected area (projected_box_area_px) are tested; the others are accepted on their box. A
  // box that shows mostly has geometry that shows (saw orbit: 7 % of the leaves tested above 0.2
  // were rejected, 60 % below 0.1), and a geometry query costs about what drawing the leaf does.
  // 1 tests every leaf whose box passed (and more: boxes may show more than their hull's area).
  double geometry_below = 0.1;
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

// Occluder selection, for the OR pass and occluder fusion: drawing an object as an occluder costs
// its triangles, and what it can hide is bounded by the pixels it covers. An object is drawn as
// an occluder when its projected bounding sphere (radius: half the box diagonal, at the box's
// nearest point) covers at least min_pixels_per_triangle pixels per triangle; dense small
// geometry (bolts, pipe runs far away) costs the OR more than it can hide. The eye in or on the
// box always keeps it. Drawing fewer occluders leaves depth farther, so queries find more
// visible, never less: conservative. 0 keeps every object.
struct OccluderSelection {
  double min_pixels_per_triangle = 0;
  bool worth(const Aabb& box, uint64_t triangles, const Camera& cam, double viewport_height_px) const;
  // Removes from `ids` (renderable ids) the objects not worth drawing as occluders.
  void filter(std::vector<uint32_t>& ids, const Renderables& r, const Camera& cam, double viewport_height_px) const;
};

// The items of the given nodes, ascending (the one draw order everywhere, so that z-ties resolve
// identically in every renderer).
std::vector<uint32_t> items_of_nodes(const Hierarchy& h, std::span<const uint32_t> nodes);

}  // namespace occ
