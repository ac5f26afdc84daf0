// Item-buffer error measures (item_diff.hpp).
#include "render_client/tools/item_diff.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <limits>
#include <span>
#include <stdexcept>

namespace occ {

ItemSpace ItemSpace::of(const Hierarchy& h) {
  ItemSpace s;
  s.items = uint32_t(h.items().size());
  for (const HNode& n : h.nodes()) s.nodes.emplace_back(n.first_item, n.item_count);
  return s;
}

std::pair<uint32_t, uint32_t> ItemSpace::range(uint32_t value) const {
  if (value == 0) return {0, 0};
  if (value <= items) return {value - 1, value};
  const uint64_t node = uint64_t(value) - items - 1;
  if (node >= nodes.size())
    throw std::runtime_error("item buffer value " + std::to_string(value) + " outside the id space (" +
                             std::to_string(items) + " items, " + std::to_string(nodes.size()) + " nodes)");
  const auto [first, count] = nodes[node];
  return {first, first + count};
}

void ItemSpace::write(const std::string& path) const {
  std::ofstream f(path);
  f << "occswitch item buffer ids 1\nitems " << items << " nodes " << nodes.size() << "\n";
  for (const auto& [first, count] : nodes) f << first << " " << count << "\n";
  if (!f) throw std::runtime_error(path + ": cannot write");
}

ItemSpace ItemSpace::read(const std::string& path) {
  std::ifstream f(path);
  std::string magic;
  std::getline(f, magic);
  if (magic != "occswitch item buffer ids 1") throw std::runtime_error(path + ": not an item buffer id space");
  std::string w1, w2;
  size_t node_count = 0;
  ItemSpace s;
  if (!(f >> w1 >> s.items >> w2 >> node_count) || w1 != "items" || w2 != "nodes")
    throw std::runtime_error(path + ": bad header");
  s.nodes.resize(node_count);
  for (auto& [first, count] : s.nodes)
    if (!(f >> first >> count) || uint64_t(first) + count > s.items)
      throw std::runtime_error(path + ": bad node line");
  return s;
}

Image encode_depth(int width, int height, const std::vector<float>& gl_depth) {
  IdImage bits{width, height, std::vector<uint32_t>(size_t(width) * height), {}};
  for (int y = 0; y < height; ++y)
    std::memcpy(&bits.ids[size_t(y) * width], &gl_depth[size_t(height - 1 - y) * width], size_t(width) * 4);
  return encode_ids(bits);
}

std::vector<float> decode_depth(const Image& img) {
  const IdImage bits = decode_ids(img);
  std::vector<float> d(bits.ids.size());
  std::memcpy(d.data(), bits.ids.data(), d.size() * 4);
  return d;
}

IdImage decode_ids(const Image& img) {
  IdImage out{img.width, img.height, std::vector<uint32_t>(size_t(img.width) * img.height), {}};
  for (size_t p = 0; p < out.ids.size(); ++p) {
    const uint8_t* c = &img.rgba[4 * p];
    out.ids[p] = uint32_t(c[0]) | uint32_t(c[1]) << 8 | uint32_t(c[2]) << 16 | uint32_t(c[3]) << 24;
  }
  return out;
}

Image encode_ids(const IdImage& ids) {
  Image img{ids.width, ids.height, std::vector<uint8_t>(ids.ids.size() * 4)};
  for (size_t p = 0; p < ids.ids.size(); ++p)
    for (int k = 0; k < 4; ++k) img.rgba[4 * p + k] = uint8_t(ids.ids[p] >> (8 * k));
  return img;
}

namespace {

// 1-D squared distance transform of f[0..n) (stride apart) in place: the lower envelope of the
// parabolas (x - q)^2 + f[q]. v, z, d: scratch of n, n + 1, n.
void distance_1d(double* f, size_t stride, int n, std::vector<int>& v, std::vector<double>& z, std::vector<double>& d) {
  int k = -1;
  for (int q = 0; q < n; ++q) {
    const double fq = f[q * stride];
    if (fq >= kFar) continue;  // no parabola
    double s = 0;
    while (k >= 0) {
      const double fv = f[v[k] * stride];
      s = ((fq + double(q) * q) - (fv + double(v[k]) * v[k])) / (2.0 * (q - v[k]));
      if (s > z[k]) break;
      --k;
    }
    ++k;
    v[k] = q;
    z[k] = k == 0 ? -kFar : s;
    z[k + 1] = kFar;
  }
  if (k < 0) return;  // no site on this line: all stay kFar
  for (int q = 0, j = 0; q < n; ++q) {
    while (z[j + 1] < q) ++j;
    const double dq = q - v[j];
    d[q] = dq * dq + f[v[j] * stride];
  }
  for (int q = 0; q < n; ++q) f[q * stride] = d[q];
}

}  // namespace

void squared_distance_transform(std::vector<double>& f, int w, int h) {
  const int n = std::max(w, h);
  std::vector<int> v(n);
  std::vector<double> z(n + 1), d(n);
  for (int x = 0; x < w; ++x) distance_1d(&f[x], size_t(w), h, v, z, d);
  for (int y = 0; y < h; ++y) distance_1d(&f[size_t(y) * w], 1, w, v, z, d);
}

namespace {

// Pixel indices grouped by a key (counting sort): key k's pixels are at[start[k] .. start[k + 1]),
// in ascending pixel order. Pixels whose key is kSkip are left out.
constexpr uint32_t kSkip = ~0u;
struct Buckets {
  std::vector<uint32_t> start, at;
  Buckets(size_t keys, const std::vector<uint32_t>& key_of_pixel) : start(keys + 1, 0) {
    for (uint32_t k : key_of_pixel)
      if (k != kSkip) ++start[k + 1];
    for (size_t k = 1; k < start.size(); ++k) start[k] += start[k - 1];
    at.resize(start.back());
    std::vector<uint32_t> fill(start.begin(), start.end() - 1);
    for (uint32_t p = 0; p < key_of_pixel.size(); ++p)
      if (key_of_pixel[p] != kSkip) at[fill[key_of_pixel[p]]++] = p;
  }
  std::span<const uint32_t> of(uint32_t first_key, uint32_t last_key) const {  // keys [first, last)
    return {at.data() + start[first_key], at.data() + start[last_key]};
  }
  std::span<const uint32_t> of(uint32_t key) const { return of(key, key + 1); }
};

// For each pixel of `queries`, the distance to the nearest pixel of `sites` (+inf: none), into
// `out`: an exact distance transform over the bounding box of both.
void nearest(const std::vector<std::span<const uint32_t>>& sites, std::span<const uint32_t> queries, int w,
             std::vector<double>& grid, std::vector<double>& out) {
  out.assign(queries.size(), std::numeric_limits<double>::infinity());
  int x0 = w, y0 = 1 << 30, x1 = -1, y1 = -1;
  auto add = [&](uint32_t p) {
    const int x = int(p % w), y = int(p / w);
    x0 = std::min(x0, x), y0 = std::min(y0, y), x1 = std::max(x1, x), y1 = std::max(y1, y);
  };
  bool any = false;
  for (const auto& s : sites) {
    any = any || !s.empty();
    for (uint32_t p : s) add(p);
  }
  if (!any || queries.empty()) return;
  for (uint32_t p : queries) add(p);
  const int bw = x1 - x0 + 1, bh = y1 - y0 + 1;
  auto cell = [&](uint32_t p) { return size_t(int(p / w) - y0) * bw + size_t(int(p % w) - x0); };
  grid.assign(size_t(bw) * bh, kFar);
  for (const auto& s : sites)
    for (uint32_t p : s) grid[cell(p)] = 0;
  squared_distance_transform(grid, bw, bh);
  for (size_t k = 0; k < queries.size(); ++k) out[k] = std::sqrt(grid[cell(queries[k])]);
}

// Per pixel: 1 where a kThickBlock x kThickBlock block of equal values holds it (the surface is
// thicker than a sliver there), else 0. Runs of equal values per row, then per column of those.
std::vector<uint8_t> thick(const IdImage& img) {
  const int w = img.width, h = img.height, k = kThickBlock;
  std::vector<uint8_t> row(img.ids.size(), 0), block(img.ids.size(), 0), t(img.ids.size(), 0);
  auto at = [&](int x, int y) { return size_t(y) * w + x; };
  for (int y = 0; y < h; ++y)  // row[x, y]: ids[x .. x + k) equal
    for (int x = 0, run = 0; x < w; ++x) {
      run = x > 0 && img.ids[at(x, y)] == img.ids[at(x - 1, y)] ? run + 1 : 1;
      if (run >= k) row[at(x - k + 1, y)] = 1;
    }
  for (int x = 0; x + k <= w; ++x)  // block[x, y]: the k x k block from (x, y) is one value
    for (int y = 0, run = 0; y < h; ++y) {
      run = row[at(x, y)] && y > 0 && row[at(x, y - 1)] && img.ids[at(x, y)] == img.ids[at(x, y - 1)] ? run + 1
            : row[at(x, y)]                                                                           ? 1
                                                                                                      : 0;
      if (run >= k) block[at(x, y - k + 1)] = 1;
    }
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      if (block[at(x, y)])
        for (int dy = 0; dy < k; ++dy)
          for (int dx = 0; dx < k; ++dx) t[at(x + dx, y + dy)] = 1;
  return t;
}

}  // namespace

ItemDiff diff_items(const ItemSpace& space, const IdImage& reference, const IdImage& frame, double tau_px) {
  if (reference.width != frame.width || reference.height != frame.height)
    throw std::runtime_error("item buffers differ in size");
  const int w = frame.width;
  const size_t np = frame.ids.size();
  const uint32_t values = space.items + uint32_t(space.nodes.size()) + 1;  // frame values 0..values-1
  for (uint32_t v : reference.ids)
    if (v > space.items) throw std::runtime_error("reference item buffer holds an HLOD (value " + std::to_string(v) + ")");
  for (uint32_t v : frame.ids)
    if (v >= values) space.range(v);  // throws
  ItemDiff r;
  r.pixels = np;
  // Where the frame's value does not hold the reference's item (background: value 0 in both).
  std::vector<uint32_t> wrong_here(np, kSkip), wrong_gone(np, kSkip);
  for (size_t p = 0; p < np; ++p) {
    const uint32_t v = frame.ids[p], u = reference.ids[p];
    r.drawn += v != 0;
    const auto [a, b] = space.range(v);
    const bool holds = v == 0 ? u == 0 : u != 0 && a <= u - 1 && u - 1 < b;
    if (!holds) wrong_here[p] = v, wrong_gone[p] = u;
  }
  const Buckets ref(space.items + 1, reference.ids), tau(values, frame.ids);
  const Buckets here(values, wrong_here), gone(space.items + 1, wrong_gone);
  // Which of the two measures a wrong pixel takes: with depth, the one of the surface that moved
  // (came: the frame's is nearer or the reference shows background; went: the frame's is farther
  // or shows background); without, the smaller.
  const bool depth = !frame.depth.empty() && frame.depth.size() == np && reference.depth.size() == np;
  auto came = [&](size_t p) {
    return reference.ids[p] == 0 || (frame.ids[p] != 0 && frame.depth[p] >= reference.depth[p]);
  };
  std::vector<double> disp(np, std::numeric_limits<double>::infinity()), grid, dist;
  for (size_t p = 0; p < np; ++p)
    if (wrong_here[p] == kSkip) disp[p] = 0;
  // Came: the frame shows v at p; the nearest reference pixel of what v holds.
  for (uint32_t v = 0; v < values; ++v) {
    const std::span<const uint32_t> q = here.of(v);
    if (q.empty()) continue;
    const auto [a, b] = space.range(v);
    nearest({v == 0 ? ref.of(0) : ref.of(a + 1, b + 1)}, q, w, grid, dist);
    for (size_t k = 0; k < q.size(); ++k)
      if (!depth || came(q[k])) disp[q[k]] = std::min(disp[q[k]], dist[k]);
  }
  // Went: the reference shows u at p; the nearest frame pixel of u or an HLOD holding it (what
  // the frame shows at p was behind it).
  std::vector<uint32_t> hlods;  // HLOD values the frame shows
  for (uint32_t v = space.items + 1; v < values; ++v)
    if (!tau.of(v).empty()) hlods.push_back(v);
  std::vector<std::span<const uint32_t>> sites;
  for (uint32_t u = 0; u <= space.items; ++u) {
    const std::span<const uint32_t> q = gone.of(u);
    if (q.empty()) continue;
    sites.assign(1, tau.of(u));
    if (u != 0)
      for (uint32_t v : hlods) {
        const auto [a, b] = space.range(v);
        if (a <= u - 1 && u - 1 < b) sites.push_back(tau.of(v));
      }
    nearest(sites, q, w, grid, dist);
    for (size_t k = 0; k < q.size(); ++k)
      if (!depth || !came(q[k])) disp[q[k]] = std::min(disp[q[k]], dist[k]);
  }
  const std::vector<uint8_t> thick_ref = thick(reference), thick_frame = thick(frame);
  for (size_t p = 0; p < np; ++p) {
    if (disp[p] > tau_px) ++r.beyond_tau;
    if (disp[p] > r.max_displacement) {
      r.max_displacement = disp[p];
      r.worst_x = int(p % w), r.worst_y = int(p / w);
    }
    if (disp[p] > 0 && (!thick_ref[p] || !thick_frame[p])) {
      ++r.thin;
      continue;
    }
    if (disp[p] > r.max_thick_displacement) {
      r.max_thick_displacement = disp[p];
      r.thick_x = int(p % w), r.thick_y = int(p / w);
    }
  }
  // Items shown in the reference and held by no value of the frame.
  std::vector<int32_t> cover(size_t(space.items) + 1, 0);  // difference array
  for (uint32_t v = 1; v < values; ++v)
    if (!tau.of(v).empty()) {
      const auto [a, b] = space.range(v);
      ++cover[a], --cover[b];
    }
  int32_t covered = 0;
  for (uint32_t i = 0; i < space.items; ++i) {
    covered += cover[i];
    const std::span<const uint32_t> px = ref.of(i + 1);
    if (px.empty()) continue;
    ++r.shown;
    if (covered != 0) continue;
    r.missing_pixels += px.size();
    bool thick_somewhere = false;
    for (uint32_t q : px) thick_somewhere = thick_somewhere || thick_ref[q];
    r.missing_thick += thick_somewhere;
    if (r.missing++ > 0) continue;
    r.first_missing = i;
    r.missing_x = int(px[0] % w), r.missing_y = int(px[0] / w);
  }
  return r;
}

}  // namespace occ
