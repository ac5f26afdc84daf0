// cull_overview: a picture of what the occlusion switch culls in one frame (the paper's colour
// plate). It replays the cluster's lockstep culling in one process up to frame F with the switch
// nodes' own cull frames (switch_node/cull_frame.hpp: the OR of frame f renders V_{f-2} and then
// the streamed additions of V_{f-1} depth-only; HC is SwitchStep with every HC choice of the
// nodes, the visibility hold included), classifies every
// non-empty leaf for frame F (visible = yellow, frustum-culled = violet, occlusion-culled =
// orange) and renders the scene from up and behind the camera, each pixel coloured by its
// node's class and shaded by the scene's own lighting, with camera F's frustum and a legend.
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/camera_path.hpp"
#include "common/cli.hpp"
#include "common/cull/culling.hpp"
#include "common/error.hpp"
#include "common/gl/context.hpp"
#include "common/gl/scene_renderer.hpp"
#include "common/image.hpp"
#include "common/gl/startup.hpp"
#include "common/setup/scene_setup.hpp"
#include "protocol/cluster/switch_step.hpp"
#include "switch_node/cull_frame.hpp"

namespace occ {
namespace {

struct Options {
  SceneOptions scene;
  std::string path = "walk:60";
  int frame = 0;
  std::string out;
  int width = 512, height = 512;            // the cluster's viewport (culling)
  int view_width = 1024, view_height = 768;  // the overview image
  double pitch_deg = 50;
  double reach = 0.3;  // overview: frames at most this fraction of the scene diagonal around the focus
  double cut = -1;  // section cut height above the eye (< 0: auto)
  GlBackend gl = GlBackend::Auto;
  ClusterConfig config;  // the switch nodes' flags (lockstep only)
  HcChoices hc;
};

enum Category : uint8_t { kNone = 0, kVisible = 1, kFrustum = 2, kOccluded = 3 };
struct Rgb {
  double r, g, b;
};
constexpr Rgb kCategoryColour[4] = {{0, 0, 0}, {255, 214, 0}, {150, 70, 255}, {255, 110, 0}};
constexpr uint8_t kBackground[3] = {16, 18, 24};

// ---- The cluster's visible set of frame F, replayed in one process (lockstep mode, tau 0): two
// cull frames, one per switch node, on one GL context, in the nodes' own schedule. Node f % 2
// does OR(f) (its V_{f-2}, then the other node's stream of frame f-1, message by message) and
// HC(f), whose stream the other node reads in turn.
std::vector<uint32_t> replay_visible_set(const LoadedScene& ls, const std::vector<Camera>& path, uint32_t last,
                                         const Options& o, CullStats& last_stats) {
  const Hierarchy& h = ls.hierarchy;
  const Enclosures sealed = find_enclosures("cull_overview", ls.scene, h);
  auto ctx = start_gl("cull_overview", o.gl, o.width, o.height);
  SceneRenderer renderer(*ctx, ls.scene, h, ls.lod.get());
  const Renderables renderables(h, ls.lod.get());
  const ClusterConfig& config = o.config;
  const Viewport vp{o.width, o.height};
  // The nodes' back end, chosen as theirs; the CPU's triangles, if it needs them, once for both
  // cull frames, as each does its OR and HC before the other starts.
  const BackendChoice choice =
      choose_backend_for(*ctx, config, o.hc, !ls.scene.mapped && !ls.scene.geometry_released());
  std::cerr << "cull_overview: " << backend_line(choice) << "\n";
  std::optional<CpuOccluders> cpu;
  if (choice.kind == BackendKind::cpu) {
    std::string why;
    cpu = CpuOccluders::copy(ls.scene, h, o.width, o.height, &why);
    if (!cpu) throw InputError("--backend cpu: " + why);
  }
  CpuOccluders* const or_cpu = cpu ? &*cpu : nullptr;
  const HcChoices hc = with_backend_defaults(o.hc, choice);
  CullFrame node0(make_backend(choice, *ctx, renderer, renderables, or_cpu, config), renderables, sealed, config, hc,
                  vp, "switch node 1");
  CullFrame node1(make_backend(choice, *ctx, renderer, renderables, or_cpu, config), renderables, sealed, config, hc,
                  vp, "switch node 0");
  CullFrame* const nodes[2] = {&node0, &node1};
  std::vector<wire::Message> stream, next;  // HC(f-1)'s messages, as the other node reads them
  for (uint32_t f = 0; f <= last; ++f) {
    CullFrame& node = *nodes[f % 2];
    node.begin_or(path[f], true);
    if (f > 0) {
      node.begin_stream(f - 1);
      for (const wire::Message& m : stream)
        if (Result<CullFrame::Stream> step = node.take(m); !step)
          throw std::logic_error("cull_overview: the replay's own stream of frame " + std::to_string(f - 1) + ": " +
                                 step.error());
    }
    next.assign(1, to_wire(f, path[f], vp));
    DiffSender out(wire::kDefaultDiffChunkIds, [&](const wire::Message& m) { next.push_back(m); });
    HcFrame hc = node.hc(f, path[f], out);
    out.send(hc.eof);
    stream.swap(next);
    last_stats = hc.stats;
    last_stats.queries = hc.eof.queries;  // the boxes the back end tested
  }
  // The hierarchy nodes V draws (at tau > 0 interior nodes' HLODs among them).
  const VisibleSet& visible = nodes[last % 2]->visible();
  std::vector<uint32_t> v;
  for (uint32_t id : visible.ids()) v.push_back(renderables.node_of(id));
  std::sort(v.begin(), v.end());
  return v;
}

// ---- The overview camera: up and behind camera F, looking a little ahead of it, pulled back
// until the scene bounds fit.
glm::dvec3 to_camera_space(const Camera& c, const glm::dvec3& p) { return glm::inverse(c.orientation) * (p - c.eye); }

bool fits(const Camera& c, const Aabb& b, double margin) {
  const double ty = std::tan(c.fovy_rad * 0.5), tx = ty * c.aspect;
  for (int i = 0; i < 8; ++i) {
    glm::dvec3 p((i & 1) ? b.max.x : b.min.x, (i & 2) ? b.max.y : b.min.y, (i & 4) ? b.max.z : b.min.z);
    glm::dvec3 q = to_camera_space(c, p);
    if (-q.z <= c.near_dist) return false;
    if (std::abs(q.x / (-q.z * tx)) > margin || std::abs(q.y / (-q.z * ty)) > margin) return false;
  }
  return true;
}

Camera overview_camera(const Camera& cam, const Aabb& bounds, double aspect, double pitch_deg, double reach_frac) {
  const double diag = bounds.diagonal();
  glm::dvec3 fh(cam.forward().x, 0, cam.forward().z);
  fh = glm::length(fh) > 1e-6 ? glm::normalize(fh) : glm::dvec3(0, 0, -1);
  // The focus: a bit ahead of the camera, kept inside the scene's footprint.
  glm::dvec3 focus = cam.eye + fh * (0.14 * diag);
  focus = glm::clamp(focus, bounds.min, bounds.max);
  focus.y = std::clamp(cam.eye.y, bounds.min.y, bounds.max.y);
  const double pitch = glm::radians(pitch_deg);
  const glm::dvec3 dir = -fh * std::cos(pitch) + glm::dvec3(0, 1, 0) * std::sin(pitch);
  const glm::dvec3 up = fh * std::sin(pitch) + glm::dvec3(0, 1, 0) * std::cos(pitch);
  // Frame the scene around the camera: its bounds, but at most `reach` from the focus
  // horizontally (a big city would otherwise shrink the camera's surroundings to a few pixels).
  const double reach = reach_frac * diag;
  Aabb frame = bounds;
  frame.min.x = std::max(frame.min.x, focus.x - reach);
  frame.max.x = std::min(frame.max.x, focus.x + reach);
  frame.min.z = std::max(frame.min.z, focus.z - reach);
  frame.max.z = std::min(frame.max.z, focus.z + reach);
  Camera ov;
  for (double d = 0.02 * diag + 1e-6; d < 20 * diag; d *= 1.02) {
    ov = Camera::look_at(focus + dir * d, focus, up, 40.0, aspect, 0.1, 1.0);
    auto_near_far(ov, bounds);
    if (fits(ov, frame, 0.96)) break;
  }
  return ov;
}

// ---- Auto section cut: if a leaf lies right above the eye (a ceiling or roof), everything that
// starts at or above it is left out of the overview, so the view from above sees inside.
double auto_cut_height(const Hierarchy& h, const std::vector<uint32_t>& leaves, const Camera& cam) {
  double lowest = std::numeric_limits<double>::infinity();
  for (uint32_t id : leaves) {
    const Aabb& b = h.node(id).box;
    if (b.min.y > cam.eye.y && cam.eye.x >= b.min.x && cam.eye.x <= b.max.x && cam.eye.z >= b.min.z &&
        cam.eye.z <= b.max.z)
      lowest = std::min(lowest, b.min.y);
  }
  return lowest;
}

// ---- Drawing on the CPU.
void blend(Image& img, int x, int y, const Rgb& c, double a) {
  if (x < 0 || y < 0 || x >= img.width || y >= img.height) return;
  uint8_t* p = &img.rgba[(size_t(y) * img.width + x) * 4];
  p[0] = uint8_t(std::lround(p[0] * (1 - a) + c.r * a));
  p[1] = uint8_t(std::lround(p[1] * (1 - a) + c.g * a));
  p[2] = uint8_t(std::lround(p[2] * (1 - a) + c.b * a));
  p[3] = 255;
}

void fill_rect(Image& img, int x0, int y0, int w, int h, const Rgb& c, double a = 1.0) {
  for (int y = y0; y < y0 + h; ++y)
    for (int x = x0; x < x0 + w; ++x) blend(img, x, y, c, a);
}

// Liang-Barsky: clips the segment to [lo, hi] in both axes; false if nothing is left.
bool clip2d(glm::dvec2& a, glm::dvec2& b, glm::dvec2 lo, glm::dvec2 hi) {
  double t0 = 0, t1 = 1;
  const glm::dvec2 d = b - a;
  const double p[4] = {-d.x, d.x, -d.y, d.y};
  const double q[4] = {a.x - lo.x, hi.x - a.x, a.y - lo.y, hi.y - a.y};
  for (int i = 0; i < 4; ++i) {
    if (p[i] == 0) {
      if (q[i] < 0) return false;
      continue;
    }
    const double t = q[i] / p[i];
    if (p[i] < 0)
      t0 = std::max(t0, t);
    else
      t1 = std::min(t1, t);
    if (t0 > t1) return false;
  }
  const glm::dvec2 a0 = a;
  a = a0 + d * t0;
  b = a0 + d * t1;
  return true;
}

// A thick line: a square brush of `size` pixels stepped along the segment.
void draw_line(Image& img, glm::dvec2 a, glm::dvec2 b, int size, const Rgb& c, double alpha) {
  if (!clip2d(a, b, {-8, -8}, {img.width + 8.0, img.height + 8.0})) return;
  const int steps = std::max(1, int(std::ceil(std::max(std::abs(b.x - a.x), std::abs(b.y - a.y)))));
  std::vector<uint8_t> done(size_t(img.width) * img.height, 0);  // no double blending
  for (int i = 0; i <= steps; ++i) {
    const glm::dvec2 p = a + (b - a) * (double(i) / steps);
    const int x0 = int(std::floor(p.x - 0.5 * size + 0.5)), y0 = int(std::floor(p.y - 0.5 * size + 0.5));
    for (int y = y0; y < y0 + size; ++y)
      for (int x = x0; x < x0 + size; ++x) {
        if (x < 0 || y < 0 || x >= img.width || y >= img.height || done[size_t(y) * img.width + x]) continue;
        done[size_t(y) * img.width + x] = 1;
        blend(img, x, y, c, alpha);
      }
  }
}

// A world-space segment seen by `ov`: clipped to its near plane, in pixels (top row = 0).
bool project_segment(const Camera& ov, int w, int h, glm::dvec3 a, glm::dvec3 b, glm::dvec2& pa, glm::dvec2& pb) {
  glm::dvec3 qa = to_camera_space(ov, a), qb = to_camera_space(ov, b);
  const double zn = -ov.near_dist;
  if (qa.z > zn && qb.z > zn) return false;
  if (qa.z > zn) qa = qb + (qa - qb) * ((zn - qb.z) / (qa.z - qb.z));
  if (qb.z > zn) qb = qa + (qb - qa) * ((zn - qa.z) / (qb.z - qa.z));
  const double ty = std::tan(ov.fovy_rad * 0.5), tx = ty * ov.aspect;
  auto px = [&](const glm::dvec3& q) {
    const double x = q.x / (-q.z * tx), y = q.y / (-q.z * ty);
    return glm::dvec2((x * 0.5 + 0.5) * w, (0.5 - y * 0.5) * h);
  };
  pa = px(qa);
  pb = px(qb);
  return true;
}

// A 5x7 bitmap font (upper case, digits, a little punctuation); lower case prints as upper.
const char* glyph(char c) {
  static const std::map<char, const char*> font = {
      {'A', ".###.#...##...#######...##...##...#"}, {'B', "####.#...##...#####.#...##...#####."},
      {'C', ".###.#...##....#....#....#...#.###."}, {'D', "###..#..#.#...##...##...##..#.###.."},
      {'E', "######....#....####.#....#....#####"}, {'F', "######....#....####.#....#....#...."},
      {'G', ".###.#...##....#.####...##...#.####"}, {'H', "#...##...##...#######...##...##...#"},
      {'I', ".###...#....#....#....#....#...###."}, {'J', "..###...#....#....#....#.#..#..##.."},
      {'K', "#...##..#.#.#..##...#.#..#..#.#...#"}, {'L', "#....#....#....#....#....#....#####"},
      {'M', "#...###.###.#.##.#.##...##...##...#"}, {'N', "#...##...###..##.#.##..###...##...#"},
      {'O', ".###.#...##...##...##...##...#.###."}, {'P', "####.#...##...#####.#....#....#...."},
      {'Q', ".###.#...##...##...##.#.##..#..##.#"}, {'R', "####.#...##...#####.#.#..#..#.#...#"},
      {'S', ".#####....#.....###.....#....#####."}, {'T', "#####..#....#....#....#....#....#.."},
      {'U', "#...##...##...##...##...##...#.###."}, {'V', "#...##...##...##...##...#.#.#...#.."},
      {'W', "#...##...##...##.#.##.#.##.#.#.#.#."}, {'X', "#...##...#.#.#...#...#.#.#...##...#"},
      {'Y', "#...##...#.#.#...#....#....#....#.."}, {'Z', "#####....#...#...#...#...#....#####"},
      {'0', ".###.#...##..###.#.###..##...#.###."}, {'1', "..#...##....#....#....#....#...###."},
      {'2', ".###.#...#....#...#...#...#...#####"}, {'3', "#####...#...#.....#.....##...#.###."},
      {'4', "...#...##..#.#.#..#.#####...#....#."}, {'5', "######....####.....#....##...#.###."},
      {'6', "..##..#...#....####.#...##...#.###."}, {'7', "#####....#...#...#...#....#....#..."},
      {'8', ".###.#...##...#.###.#...##...#.###."}, {'9', ".###.#...##...#.####....#...#..##.."},
      {'-', "...............#####..............."}, {':', "......##...##.........##...##......"},
      {'=', "..........#####.....#####.........."}, {'.', ".........................##...##..."},
      {',', "....................##....#...#...."}, {'(', "...#...#...#....#....#.....#.....#."},
      {')', ".#.....#.....#....#....#...#...#..."}, {'/', "......#...#...#...#...#............"},
      {'|', "..#....#....#....#....#....#....#.."}, {' ', "..................................."},
  };
  auto it = font.find(char(std::toupper(static_cast<unsigned char>(c))));
  return it == font.end() ? font.at(' ') : it->second;
}

int text_width(const std::string& s, int scale) { return int(s.size()) * 6 * scale; }

void draw_text(Image& img, int x, int y, const std::string& s, int scale, const Rgb& c) {
  for (char ch : s) {
    const char* g = glyph(ch);
    for (int r = 0; r < 7; ++r)
      for (int k = 0; k < 5; ++k)
        if (g[r * 5 + k] == '#') fill_rect(img, x + k * scale, y + r * scale, scale, scale, c);
    x += 6 * scale;
  }
}

// ---- The overview image.
Image compose(const Image& shaded, const Image& ids, const std::vector<uint8_t>& category) {
  Image out{shaded.width, shaded.height, std::vector<uint8_t>(shaded.rgba.size())};
  const int w = shaded.width, h = shaded.height;
  auto id_at = [&](int x, int y) -> uint32_t {
    const uint8_t* p = &ids.rgba[(size_t(y) * w + x) * 4];
    return uint32_t(p[0]) | uint32_t(p[1]) << 8 | uint32_t(p[2]) << 16 | uint32_t(p[3]) << 24;
  };
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      uint8_t* o = &out.rgba[(size_t(y) * w + x) * 4];
      const uint8_t* s = &shaded.rgba[(size_t(y) * w + x) * 4];
      const uint32_t id = id_at(x, y);
      o[3] = 255;
      if (id == 0 || id - 1 >= category.size() || category[id - 1] == kNone) {
        for (int k = 0; k < 3; ++k) o[k] = kBackground[k];
        continue;
      }
      // Luminance of the shaded pixel keeps the shapes readable; node borders are darkened.
      const double lum = (0.299 * s[0] + 0.587 * s[1] + 0.114 * s[2]) / 255.0;
      double k = std::clamp(0.15 + 1.1 * lum, 0.0, 1.0);
      bool border = false;
      for (auto [dx, dy] : {std::pair{1, 0}, {0, 1}, {-1, 0}, {0, -1}}) {
        const int nx = x + dx, ny = y + dy;
        if (nx >= 0 && ny >= 0 && nx < w && ny < h && id_at(nx, ny) != id) border = true;
      }
      if (border) k *= 0.7;
      const Rgb& c = kCategoryColour[category[id - 1]];
      o[0] = uint8_t(std::lround(c.r * k));
      o[1] = uint8_t(std::lround(c.g * k));
      o[2] = uint8_t(std::lround(c.b * k));
    }
  return out;
}

void draw_frustum(Image& img, const Camera& ov, const Camera& cam, double far_dist) {
  const double ty = std::tan(cam.fovy_rad * 0.5), tx = ty * cam.aspect;
  glm::dvec3 corner[8];
  for (int i = 0; i < 8; ++i) {
    const double d = (i & 4) ? far_dist : cam.near_dist;
    corner[i] = cam.eye + cam.forward() * d + cam.right() * (((i & 1) ? 1 : -1) * d * tx) +
                cam.up() * (((i & 2) ? 1 : -1) * d * ty);
  }
  std::vector<std::pair<glm::dvec2, glm::dvec2>> edges;
  for (int i = 0; i < 8; ++i)
    for (int bit : {1, 2, 4}) {
      const int j = i | bit;
      if (j == i) continue;
      glm::dvec2 a, b;
      if (project_segment(ov, img.width, img.height, corner[i], corner[j], a, b)) edges.emplace_back(a, b);
    }
  // The rays from the eye to the near corners are too short to see: mark the eye with a dot.
  for (auto& [a, b] : edges) draw_line(img, a, b, 4, {0, 0, 0}, 0.45);
  for (auto& [a, b] : edges) draw_line(img, a, b, 2, {255, 255, 255}, 1.0);
  glm::dvec2 e, e2;
  if (project_segment(ov, img.width, img.height, cam.eye, cam.eye, e, e2)) {
    const int r = std::max(3, img.width / 200);
    for (int y = -r - 1; y <= r + 1; ++y)
      for (int x = -r - 1; x <= r + 1; ++x) {
        const double d = std::sqrt(double(x * x + y * y));
        if (d <= r + 1) blend(img, int(e.x) + x, int(e.y) + y, d <= r ? Rgb{255, 255, 255} : Rgb{0, 0, 0}, d <= r ? 1.0 : 0.6);
      }
  }
}

// The legend goes into the corner where it hides the fewest scene pixels (`ids`: the id buffer).
void draw_legend(Image& img, const Image& ids, uint32_t frame, const uint32_t counts[4]) {
  const int scale = img.width >= 640 ? 2 : 1;
  const int line = 11 * scale, sq = 8 * scale, pad = 6 * scale;
  const std::string labels[3] = {"visible " + std::to_string(counts[kVisible]),
                                 "frustum culled " + std::to_string(counts[kFrustum]),
                                 "occlusion culled " + std::to_string(counts[kOccluded])};
  const std::string title = "frame " + std::to_string(frame);
  int wmax = text_width(title, scale);
  for (auto& l : labels) wmax = std::max(wmax, sq + 4 * scale + text_width(l, scale));
  const int pw = wmax + 2 * pad, ph = 4 * line + 2 * pad - 4 * scale;
  int x0 = pad, y0 = img.height - ph - pad;
  size_t best = SIZE_MAX;
  for (auto [cx, cy] : {std::pair{pad, img.height - ph - pad}, {pad, pad}, {img.width - pw - pad, pad},
                        {img.width - pw - pad, img.height - ph - pad}}) {
    size_t covered = 0;
    for (int y = std::max(0, cy); y < std::min(img.height, cy + ph); ++y)
      for (int x = std::max(0, cx); x < std::min(img.width, cx + pw); ++x) {
        const uint8_t* p = &ids.rgba[(size_t(y) * ids.width + x) * 4];
        covered += (p[0] | p[1] | p[2] | p[3]) != 0;
      }
    if (covered < best) {
      best = covered;
      x0 = cx;
      y0 = cy;
    }
  }
  fill_rect(img, x0, y0, pw, ph, {0, 0, 0}, 0.6);
  draw_text(img, x0 + pad, y0 + pad, title, scale, {235, 235, 235});
  for (int i = 0; i < 3; ++i) {
    const int y = y0 + pad + (i + 1) * line;
    fill_rect(img, x0 + pad, y - scale / 2, sq, sq, kCategoryColour[i + 1]);
    draw_text(img, x0 + pad + sq + 4 * scale, y, labels[i], scale, {235, 235, 235});
  }
}

int run(const Options& o) {
  if (o.out.empty()) throw InputError("--out FILE.png is required");
  if (o.config.camera_mode != CameraMode::lockstep)
    throw InputError("--camera-mode latest: cull_overview replays the switch in lockstep (frame f, camera f)");
  LoadedScene ls = load_and_build(o.scene, "cull_overview", o.config.lod());
  const Hierarchy& h = ls.hierarchy;
  const Aabb bounds = ls.scene.bounds();
  const std::vector<Camera> path = load_camera_path(o.path, bounds, {o.width, o.height});
  if (size_t(o.frame) >= path.size())
    throw InputError("--frame '" + std::to_string(o.frame) + "': the path '" + o.path + "' has " +
                     std::to_string(path.size()) + " frames (0.." + std::to_string(path.size() - 1) + ")");
  const uint32_t frame = uint32_t(o.frame);
  const Camera& cam = path[frame];

  CullStats stats;
  const std::vector<uint32_t> visible = replay_visible_set(ls, path, frame, o, stats);

  // Classify every non-empty leaf. Ids are breadth-first: a parent comes before its children.
  const Frustum fr = cam.frustum();
  std::vector<uint8_t> outside(h.size(), 0), category(h.size(), kNone);
  for (uint32_t id = 0; id < h.size(); ++id) {
    const HNode& n = h.node(id);
    outside[id] = (n.parent != kNoNode && outside[n.parent]) || fr.classify(n.box) == Containment::Outside;
  }
  std::vector<uint32_t> leaves;
  uint32_t counts[4] = {};
  for (uint32_t id = 0; id < h.size(); ++id) {
    const HNode& n = h.node(id);
    if (!n.leaf() || n.item_count == 0) continue;
    leaves.push_back(id);
    category[id] = outside[id] ? kFrustum : kOccluded;
  }
  // A leaf shows when V holds it or (an HLOD) an ancestor; ids are breadth-first.
  std::vector<uint8_t> drawn(h.size(), 0);
  for (uint32_t id : visible) drawn[id] = 1;
  for (uint32_t id = 0; id < h.size(); ++id)
    if (h.node(id).parent != kNoNode && drawn[h.node(id).parent]) drawn[id] = 1;
  for (uint32_t id : leaves)
    if (drawn[id]) category[id] = kVisible;
  for (uint32_t id : leaves) ++counts[category[id]];

  // The overview: the leaves below the section cut, shaded and as an id buffer.
  double cut = std::numeric_limits<double>::infinity();
  if (o.cut >= 0)
    cut = cam.eye.y + o.cut;
  else
    cut = auto_cut_height(h, leaves, cam);
  std::vector<uint32_t> shown;
  for (uint32_t id : leaves)
    if (h.node(id).box.min.y < cut) shown.push_back(id);
  const Camera ov = overview_camera(cam, bounds, double(o.view_width) / o.view_height, o.pitch_deg, o.reach);
  Image shaded, ids;
  {
    auto ctx = GlContext::create(o.gl, o.view_width, o.view_height);
    SceneRenderer renderer(*ctx, ls.scene, h);
    renderer.begin_frame(ov, true);
    renderer.draw_items(items_of_nodes(h, shown), SceneRenderer::Mode::Shaded);
    shaded = ctx->read_rgba();
    renderer.begin_id_frame(ov);
    renderer.draw_nodes_ids(shown);
    ids = ctx->read_rgba();
  }
  Image img = compose(shaded, ids, category);
  draw_frustum(img, ov, cam, std::min(cam.far_dist, bounds.diagonal() * 0.3));
  draw_legend(img, ids, frame, counts);

  const std::filesystem::path out(o.out);
  if (out.has_parent_path()) std::filesystem::create_directories(out.parent_path());
  write_png(o.out, img);
  std::printf("cull_overview: frame %u: visible %u, frustum-culled %u, occlusion-culled %u, leaves %zu, queries %u%s\n",
              frame, counts[kVisible], counts[kFrustum], counts[kOccluded], leaves.size(), stats.queries,
              std::isfinite(cut) ? (", section cut at y=" + std::to_string(cut)).c_str() : "");
  return 0;
}

}  // namespace
}  // namespace occ

int main(int argc, char** argv) {
  return occ::run_main([&] {
    occ::Options o;
    occ::Cli cli("cull_overview", "--scene S --path P --frame F --out FILE.png [switch_node's options]",
                 "Replays the occlusion switch's culling (lockstep, one process) up to frame F and draws an\n"
                 "overview from up and behind camera F: visible nodes yellow, frustum-culled violet,\n"
                 "occlusion-culled orange, with the camera's frustum and a legend. It takes the switch\n"
                 "nodes' scene, accuracy and culling options, so their command line replays as it ran.");
    cli.group(occ::CliGroup::scene);
    cli.option("path", &o.path, "P", "camera path: file.csv, orbit:N, walk:N or fly:N");
    cli.option("frame", &o.frame, 0, 10000000, "the frame to show");
    occ::add_view_options(cli, o.scene, &o.width, &o.height, &o.gl, "the cluster's, for culling");
    occ::add_cluster_options(cli, o.config);
    occ::add_hc_options(cli, o.hc);
    cli.group(occ::CliGroup::output);
    cli.option("out", &o.out, "FILE.png", "the overview image");
    cli.option("view-width", &o.view_width, 16, occ::kMaxViewportPx, "overview image width");
    cli.option("view-height", &o.view_height, 16, occ::kMaxViewportPx, "overview image height");
    cli.option("pitch", &o.pitch_deg, 10.0, 89.0, "overview: degrees above the horizon");
    cli.option("reach", &o.reach, 0.05, 10.0,
               "overview: frame the scene up to this fraction of its diagonal around the camera");
    cli.option("cut", &o.cut, -1.0, 1e9,
               "overview: leave out leaves starting this far above the eye (-1: auto, cut at a ceiling "
               "right above the eye)");
    if (!cli.parse(argc, argv)) return 0;
    return occ::run(o);
  });
}
