// The tau > 0 error bound a user can check (frame_diff --items): an item buffer of the
// full-detail reference against one of a tau frame, both written by render_client --images items.
//
// Item buffers (DIR/items_NNNNN.png, RGBA8 read as a little-endian u32 per pixel, the frames'
// sizes): 0 = nothing drawn; 1..I = item index + 1 (an item = object x mesh cluster, drawn at full
// detail or at a simplified leaf level); I + 1 .. I + N = I + node id + 1, an interior node drawn
// as its HLOD, which holds the items [first_item, first_item + item_count) of its subtree.
// DIR/items.txt (ItemSpace) says I and every node's item range. BLEND items (glass) are not in
// item buffers (what shows through glass is). The measures are per item, which bounds the same
// measures per object: an object is missing only when all its shown items are, and the nearest
// pixel of the same item is never nearer than the nearest of the same object.
//
// Per frame (ItemDiff):
//   missing           items the reference shows in at least one pixel that the tau frame shows
//                     at no level (neither the item nor an HLOD holding it); the promise is 0;
//   max_displacement  over the pixels where the tau frame's id does not hold the reference's item,
//                     the screen-space displacement of the surface that made the pixel wrong (in
//                     pixels, centre to centre): where the frame's surface is nearer than the
//                     reference's there (or the reference shows background), it came: the distance
//                     to the nearest reference pixel of what the frame shows (the measure);
//                     where it is farther (or the frame shows background), the reference's surface
//                     went and uncovered it: the distance to the nearest frame pixel of that surface
//                     (itself or an HLOD holding it). Without the depth files, the smaller of the
//                     two. The promise is <= tau + 1 (rasterisation). The second case matters: a
//                     wall whose top edge moves down a pixel uncovers an object whose nearest
//                     reference pixel is 61 pixels away (plant:0.05 orbit:20, tau 1, frame 13);
//   beyond_tau        pixels whose displacement exceeds tau (+inf: explained by neither);
//   max_thick_displacement, missing_thick  the same without slivers: pixels where the reference or
//                     the frame shows a surface at most two pixels thick (no 3 x 3 block of its id
//                     holds the pixel), items that are slivers wherever the reference shows them.
//                     A sliver moved or thinned by less than a pixel can miss every pixel centre
//                     along its length, so its pixels vanish or appear in runs whatever tau (a
//                     pipe of plant:0.05 at tau 1: 10 pixels; a one-pixel object of plant:0.3 at
//                     tau 0.5: gone). This is the bound that holds (docs/output.md).
// Cost: one exact squared Euclidean distance transform (Felzenszwalb & Huttenlocher, two passes
// of the 1-D lower envelope of parabolas) per distinct id with wrong pixels, over the bounding box
// of those and of the pixels they are measured to: linear in that box's area.
#pragma once
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "common/scene/hierarchy.hpp"
#include "common/image.hpp"

namespace occ {

// The id space of an item buffer (DIR/items.txt).
struct ItemSpace {
  uint32_t items = 0;
  std::vector<std::pair<uint32_t, uint32_t>> nodes;  // per node: first item, item count
  static ItemSpace of(const Hierarchy& h);
  // The items [first, last) a pixel value holds (value 0: {0, 0}); throws std::runtime_error
  // for a value outside the space.
  std::pair<uint32_t, uint32_t> range(uint32_t value) const;
  void write(const std::string& path) const;
  static ItemSpace read(const std::string& path);  // throws std::runtime_error naming the file
  bool operator==(const ItemSpace&) const = default;
};

// An item buffer's pixel values, row-major, top row first, and its depth (reverse-Z: larger is
// nearer; empty: unknown).
struct IdImage {
  int width = 0, height = 0;
  std::vector<uint32_t> ids;
  std::vector<float> depth;
};
IdImage decode_ids(const Image& img);
Image encode_ids(const IdImage& ids);  // the RGBA8 form (tests)
// Depth as RGBA8 (each float's bits, little-endian); `gl_depth` bottom row first (glReadPixels),
// the image top row first like every frame.
Image encode_depth(int width, int height, const std::vector<float>& gl_depth);
std::vector<float> decode_depth(const Image& img);  // top row first

struct ItemDiff {
  uint64_t shown = 0;    // items the reference shows
  uint64_t missing = 0;  // of them, shown at no level by the tau frame
  uint64_t pixels = 0;   // pixels of the frame
  uint64_t drawn = 0;    // pixels the tau frame shows an item or HLOD in
  double max_displacement = 0;
  int worst_x = -1, worst_y = -1;  // a pixel at max_displacement
  uint64_t beyond_tau = 0;  // pixels displaced by more than tau
  // The same maximum without the displaced pixels where the reference or the frame shows a sliver
  // (no kThickBlock x kThickBlock block of its id holds the pixel), and how many those are.
  double max_thick_displacement = 0;
  int thick_x = -1, thick_y = -1;
  uint64_t thin = 0;
  uint64_t missing_pixels = 0;  // reference pixels of the missing items
  uint64_t missing_thick = 0;   // missing items thicker than a sliver somewhere in the reference
  uint32_t first_missing = 0;   // the lowest missing item (when missing > 0) and a pixel of it
  int missing_x = -1, missing_y = -1;
};
// Throws std::runtime_error when the sizes differ or a value is outside `space`.
ItemDiff diff_items(const ItemSpace& space, const IdImage& reference, const IdImage& frame, double tau_px);

// Exact squared Euclidean distance transform in place: `f` (w x h, row-major) holds 0 at sites
// and kFar elsewhere; afterwards each entry is the squared distance to the nearest site (kFar
// or more where there is none). Linear in w * h.
constexpr double kFar = 1e20;
// A surface is thicker than a sliver at a pixel when a block of this many pixels square of its id
// holds the pixel.
constexpr int kThickBlock = 3;
void squared_distance_transform(std::vector<double>& f, int w, int h);

}  // namespace occ
