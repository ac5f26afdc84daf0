// Numerical hard cases through the three real processes: each pins exact cameras on a
// generated hard-case scene (common/scene/scene_io.hpp, hard:* and offset:*) and requires the cluster
// frame to equal the reference frame (no culling) for every frame: culling must stay
// conservative however degenerate the camera or the geometry.
#include <gtest/gtest.h>

#include <cmath>

#include "hard_util.hpp"

using namespace occtest;
using occ::Camera;

namespace {

const std::string kWalls = "hard:walls";  // walls at x = 10..50, see scene_io.hpp

// Camera inside node boxes: inside the open box (looking out of its open face and back into it),
// inside a closed cube (only its inner faces show), inside the flat box of a wall.
std::vector<Camera> inside_box_path() {
  return {
      cam({-12, 1.5, 0}, {0, 1.5, 0}),           // outside, approaching the open box
      cam({-6.5, 1.5, 0}, {10, 1.5, 0}),         // inside the open box, looking out
      cam({-6.5, 1.5, 0}, {-20, 1.5, 0.3}),      // inside the open box, looking at its back wall
      cam({15, 0.5, 0}, {30, 0.5, 0}),           // inside wall 1's middle cube, looking +x
      cam({15, 0.5, 0}, {0, 0.5, 0}),            // same, looking back at wall 1
      cam({9, 1, 3}, {20, 1, 3}),                // out again (the cube was the occluder)
  };
}

// The eye exactly on box faces, edges and corners (closed boxes: a point on a face is inside).
std::vector<Camera> on_face_path() {
  return {
      cam({-5, 1.5, 0}, {10, 1.5, 0}),           // on the plane of the open box's missing face
      cam({14.5, 0.5, 0}, {30, 0.5, 0}),         // on cube's -x face, looking into the cube
      cam({14.5, 0.5, 0}, {0, 0.5, 0.2}),        // same point, looking away
      cam({10, 2, 3}, {20, 2, 3}),               // on wall 1 (a zero-thickness box), looking +x
      cam({10, 2, 3}, {0, 2, 3}),                // on wall 1, looking -x
      cam({5, 0, 3}, {20, 0, 3}),                // on the ground plane, looking along it
      cam({14.5, 1, -0.5}, {30, 0, -8}),         // on a cube corner
      cam({10, 4, 3}, {20, 4, 3}),               // on the top edge of wall 1
  };
}

// Walking through a wall: the eye crosses wall 1 (x = 10, solid at z = 3) while the near plane
// (0.05 ahead) crosses it first; then the same backwards, and with near = 1e-3.
std::vector<Camera> through_wall_path() {
  std::vector<Camera> p;
  for (double x : {9.0, 9.9, 9.95, 9.96, 9.99, 9.999, 10.0, 10.001, 10.01, 10.04, 10.1, 11.0})
    p.push_back(cam({x, 2, 3}, {x + 10, 2, 3}));
  for (double x : {11.0, 10.06, 10.04, 10.0, 9.96, 9.9})  // backwards, looking -x
    p.push_back(cam({x, 2, 3}, {x - 10, 2, 3}));
  for (double x : {9.99, 9.9995, 10.0005, 10.01}) p.push_back(cam({x, 2, 3}, {x + 10, 2, 3.1}, 60, 1e-3));
  return p;
}

// Zero-thickness walls seen exactly edge-on (the edge-on wall in the plane z = 8, the walls x =
// 10k from their own plane) and nearly edge-on.
std::vector<Camera> edge_on_path() {
  return {
      cam({-2, 2, 8}, {60, 2, 8}),     cam({-2, 2, 8.001}, {60, 2, 8.001}), cam({-2, 2, 7.999}, {60, 2, 7.999}),
      cam({-2, 2, 8}, {60, 2, 7.5}),   cam({10, 1, -10}, {10, 1, 10}),      cam({10, 1, -10}, {10.01, 1, 10}),
      cam({-10, 0, 0}, {60, 0, 0.1}),  // the flat ground, edge-on
  };
}

// Boxes exactly on the frustum planes: fovy 90 and a square viewport, so the side planes are at
// 45 degrees; cube corners of wall 1's cubes (x 14.5..15.5, y 0..1, z -4.5..-3.5, -0.5..0.5,
// 3.5..4.5) put exactly on each plane, a cube face exactly at the near and at the far distance.
std::vector<Camera> frustum_plane_path() {
  std::vector<Camera> p;
  // Looking +x from x = 12 (depth d = x - 12): a point is on the right plane when z - ez = d, on
  // the left when ez - z = d, on the top when y - ey = d, on the bottom when ey - y = d.
  p.push_back(cam({12, 0.5, -2.0}, {13, 0.5, -2.0}, 90, 0.05, 500));  // middle cube inside, corner on right
  p.push_back(cam({12, 0.5, -4.0}, {13, 0.5, -4.0}, 90, 0.05, 500));  // middle cube outside, edge on right
  p.push_back(cam({12, 0.5, 4.0}, {13, 0.5, 4.0}, 90, 0.05, 500));    // middle cube outside, edge on left
  p.push_back(cam({12, -3.5, 0}, {13, -3.5, 0}, 90, 0.05, 500));      // middle cube outside, edge on top
  p.push_back(cam({12, 4.5, 0}, {13, 4.5, 0}, 90, 0.05, 500));        // middle cube outside, edge on bottom
  p.push_back(cam({12, 1.5, 0}, {13, 1.5, 0}, 90, 0.05, 500));        // cube top edge y=1 inside, on bottom
  p.push_back(cam({14.45, 0.5, 0}, {20, 0.5, 0}, 90, 0.05, 500));     // cube face at the near distance
  p.push_back(cam({11, 0.5, 0}, {20, 0.5, 0}, 90, 0.05, 3.5));        // cube face at the far distance
  p.push_back(cam({11, 0.5, 0}, {20, 0.5, 0}, 90, 0.05, 3.5000001));  // just beyond it
  return p;
}

// fovy near 1 degree (a telescope through the doors) and near 170 degrees (and 179) close to a wall.
std::vector<Camera> fovy_path() {
  return {
      cam({-30, 1.2, 0}, {60, 1.2, 0}, 1.0),   cam({-30, 1.2, 0}, {54.5, 0.5, -0.2}, 0.5),
      cam({9, 2, 3}, {20, 2, 3}, 170.0),       cam({9.5, 2, 0}, {20, 2, 0}, 170.0),
      cam({9.5, 2, 0}, {20, 1, 0.5}, 179.0),   cam({25, 6, 0}, {25, 0, 0.01}, 170.0),
  };
}

// Near 1e-3 / far 1e6 (a depth range of 1e9): occluders and occludees close together far away,
// and right in front of the eye.
std::vector<Camera> extreme_near_far_path() {
  std::vector<Camera> p;
  for (double x : {-300.0, -1000.0, -1e4}) p.push_back(cam({x, 1.3, 2.8}, {50, 0.8, 2.9}, 2.0, 1e-3, 1e6));
  p.push_back(cam({9.998, 2, 3}, {20, 2, 3}, 60, 1e-3, 1e6));
  p.push_back(cam({9.9985, 2, 3}, {20, 2, 3}, 60, 1e-3, 1e6));
  p.push_back(cam({14.499, 0.5, 0}, {0, 0.5, 0}, 60, 1e-3, 1e6));
  return p;
}

}  // namespace

TEST(HardCases, CameraInsideNodeBoxes) {
  expect_cluster_equals_reference("inside", kWalls, inside_box_path());
}

TEST(HardCases, CameraExactlyOnBoxFacesEdgesAndCorners) {
  expect_cluster_equals_reference("onface", kWalls, on_face_path());
}

TEST(HardCases, WalkingThroughAWallWhileItCrossesTheNearPlane) {
  expect_cluster_equals_reference("throughwall", kWalls, through_wall_path());
}

TEST(HardCases, ZeroThicknessWallsSeenEdgeOn) {
  expect_cluster_equals_reference("edgeon", kWalls, edge_on_path());
}

TEST(HardCases, BoxesExactlyOnTheFrustumPlanes) {
  expect_cluster_equals_reference("frustumplanes", kWalls, frustum_plane_path(), View{96, 96});
}

TEST(HardCases, FovyOneDegreeAndOneHundredSeventyDegrees) {
  expect_cluster_equals_reference("fovy", kWalls, fovy_path());
}

TEST(HardCases, NearOneThousandthFarOneMillion) {
  expect_cluster_equals_reference("nearfar", kWalls, extreme_near_far_path());
}

// Tiny parts (1e-3) in a huge hall (1e5): near/far chosen per view, including 1e-4 .. 2e5.
TEST(HardCases, TinyPartsInAHugeHall) {
  std::vector<Camera> p = {
      cam({-0.02, 1.002, 0.001}, {0, 1.002, 0.001}, 40, 1e-4, 2e5),        // plate, hidden + peeking part
      cam({-0.005, 1.0005, 0.0005}, {0.001, 1.0005, 0.0005}, 60, 1e-4, 2e5),  // right at the 1e-3 part
      cam({-3, 2, -1}, {5, 1, 0}, 60, 1e-3, 2e5),                          // the bench: parts go sub-pixel
      cam({-4e4, 1e4, -4e4}, {0, 0, 0}, 60, 1.0, 2e5),                     // the whole hall
      cam({0.0005, 1.0005, 0.5}, {0.0005, 1.0005, -1}, 90, 1e-5, 1e6),     // 1e-5 .. 1e6
  };
  expect_cluster_equals_reference("span", "hard:span", p);
}

TEST(HardCases, DegenerateHugeAndSubPixelTriangles) {
  std::vector<Camera> p = {
      cam({0, 1.5, 0}, {10, 1, 0}),                                // degenerate meshes, huge ground
      cam({4, 1.2, -1.5}, {5, 1, -2}, 60, 1e-3, 1e4),              // close to the zero-area triangles
      cam({5, 1, 2}, {6, 1, 2}, 60, 1e-3, 1e4),                    // the eye on the single-point mesh
      cam({8.5, 0.5, 0}, {9, 0.5, 0}, 60, 1e-3, 1e4),              // inside the cube with degenerate tris
      cam({10, 1.5, -1.5}, {40, 1.5, -1.5}, 60, 0.05, 1e4),        // sub-pixel field behind/beside the wall
      cam({15, 1.5, 8}, {35, 1.5, -1}, 30, 0.05, 1e4),             // the field from the side
      cam({0, 0, 0}, {10, 0, 0.3}, 60, 0.05, 1e4),                 // eye on the huge ground triangle
      cam({0, 3e5, 0}, {1, 0, 0}, 60, 1.0, 1e6),                   // the huge triangles from far above
  };
  expect_cluster_equals_reference("degenerate", "hard:degenerate", p);
}

// Tiny, huge and extreme-aspect viewports (the viewport is per process: one cluster run each).
static std::vector<Camera> viewport_path() {
  return {cam({-12, 1.5, 0}, {0, 1.5, 0}), cam({9.96, 2, 3}, {20, 2, 3}), cam({15, 0.5, 0}, {30, 0.5, 0.3}),
          cam({25, 30, -20}, {25, 0, 0})};
}

TEST(HardCases, TinyViewport16x16) {
  expect_cluster_equals_reference("vp16", kWalls, viewport_path(), View{16, 16});
}

TEST(HardCases, AspectTenToOne) {
  expect_cluster_equals_reference("vp10to1", kWalls, viewport_path(), View{640, 64});
}

TEST(HardCases, AspectOneToTen) {
  expect_cluster_equals_reference("vp1to10", kWalls, viewport_path(), View{64, 640});
}

TEST(HardCases, HugeViewports) {
  const std::vector<Camera> all = viewport_path();
  const std::vector<Camera> two(all.begin(), all.begin() + 2);
  expect_cluster_equals_reference("vp4096x512", kWalls, two, View{4096, 512});
  expect_cluster_equals_reference("vp2048", kWalls, {all[1]}, View{2048, 2048});
}

// A box edge a thousandth of a pixel off a pixel centre: on city:6x6:3:10:1 (cameras 315-316 of
// its walk:2000, 96x72), a building's side wall seen almost edge-on covers one pixel column (8
// px) because the rasteriser snaps the wall's edge onto the pixel centres, while the building's
// exact box edge, 0.002 px outside, covered none: HC culled the building and the frame missed
// the column. Boxes are now padded by sub-pixel steps on screen (box_query.hpp kPadSubpixels).
TEST(HardCases, ABoxEdgeSnappedOntoPixelCentresStillCoversThem) {
  const std::vector<Camera> p = {
      cam({-118.3407703851926, 1.7, 0.70050851583035256}, {-117.36197277275105, 1.7, 0.90533828387862547},
          59.999999999999993, 0.0040342357458452091, 403.42357458452091),
      cam({-118.16788394197098, 1.7, 0.70202336936051157}, {-117.1892022882563, 1.7, 0.90740647646109407},
          59.999999999999993, 0.0040327825518567343, 403.2782551856734),
  };
  expect_cluster_equals_reference("snapped_edge", "city:6x6:3:10:1", p, View{96, 72});
}
