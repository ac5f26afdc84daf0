#include "protocol/cluster/cluster.hpp"

#include <algorithm>
#include <iostream>
#include <tuple>
#include <utility>
#include <vector>

#include "common/cli.hpp"
#include "common/error.hpp"
#include "common/hash.hpp"

namespace occ {

wire::Camera to_wire(uint32_t number, const Camera& c, const Viewport& vp, uint8_t occlusion) {
  wire::Camera w;
  w.frame = number;
  for (int i = 0; i < 3; ++i) w.eye[i] = c.eye[i];
  w.orientation[0] = c.orientation.w;
  w.orientation[1] = c.orientation.x;
  w.orientation[2] = c.orientation.y;
  w.orientation[3] = c.orientation.z;
  w.fovy_rad = c.fovy_rad;
  w.aspect = c.aspect;
  w.near_dist = c.near_dist;
  w.far_dist = c.far_dist;
  w.viewport_width_px = uint32_t(vp.width);
  w.viewport_height_px = uint32_t(vp.height);
  w.occlusion = occlusion;
  w.section_count = c.sections.count;
  for (int i = 0; i < c.sections.count; ++i) {
    const Plane& p = c.sections.planes[size_t(i)];
    const double abcd[4] = {p.n.x, p.n.y, p.n.z, p.d};
    std::copy(abcd, abcd + 4, w.sections[i]);
  }
  return w;
}

Camera from_wire(const wire::Camera& w) {
  Camera c;
  c.eye = {w.eye[0], w.eye[1], w.eye[2]};
  c.orientation = glm::dquat(w.orientation[0], w.orientation[1], w.orientation[2], w.orientation[3]);
  c.fovy_rad = w.fovy_rad;
  c.aspect = w.aspect;
  c.near_dist = w.near_dist;
  c.far_dist = w.far_dist;
  for (int i = 0; i < w.section_count && i < Sections::kMax; ++i) {  // unit normals (wire.hpp checks)
    c.sections.planes[size_t(i)] = Plane{{w.sections[i][0], w.sections[i][1], w.sections[i][2]}, w.sections[i][3]};
    c.sections.count = uint8_t(i + 1);
  }
  return c;
}

std::optional<std::string> viewport_mismatch(const wire::Camera& w, const Viewport& vp) {
  if (w.viewport_width_px == uint32_t(vp.width) && w.viewport_height_px == uint32_t(vp.height)) return std::nullopt;
  return "camera " + std::to_string(w.frame) + " is for a " + std::to_string(w.viewport_width_px) + "x" +
         std::to_string(w.viewport_height_px) + " viewport, this process renders " + std::to_string(vp.width) + "x" +
         std::to_string(vp.height);
}

const char* camera_mode_name(CameraMode m) { return m == CameraMode::lockstep ? "lockstep" : "latest"; }

wire::Hello make_hello(wire::Role role, uint8_t node_id, const Viewport& vp, uint64_t scene_fingerprint,
                       const BuildParams& build, const ClusterConfig& config, const std::string& name,
                       const std::string& occlusion_backend) {
  wire::Hello h;
  h.role = role;
  h.node_id = node_id;
  h.viewport_width_px = uint32_t(vp.width);
  h.viewport_height_px = uint32_t(vp.height);
  h.scene_fingerprint = scene_fingerprint;
  h.arity = build.arity;
  h.leaf_items = build.leaf_items;
  h.cluster_triangles = build.cluster_triangles;
  h.config_hash = config.hash();
  h.name = name;
  h.occlusion_backend = occlusion_backend;
  return h;
}

uint64_t ClusterConfig::hash() const {
  // The flag words, as the command lines spell them.
  auto on_off = [](bool b) { return b ? "on" : "off"; };
  Hasher h;
  h.str(camera_mode_name(camera_mode));
  h.f64(pixel_error);
  h.str(on_off(visible_pixel_lod));
  h.str(on_off(front_tracking));
  return h.value();
}

void add_cluster_options(Cli& cli, ClusterConfig& c) {
  cli.group(CliGroup::cluster);
  cli.choice<CameraMode>("camera-mode", &c.camera_mode,
                         {{"lockstep", CameraMode::lockstep}, {"latest", CameraMode::latest}},
                         "lockstep: frame f uses camera f (reproducible); latest: nodes take the newest camera");
  cli.group(CliGroup::accuracy);
  cli.option("pixel-error", &c.pixel_error, 0.0, 1e6,
             "tau: screen-space error bound in pixels for LOD/HLOD selection (0 = original geometry, conservative)");
  cli.on_off("visible-pixel-lod", &c.visible_pixel_lod,
             "stop refining a node whose occlusion query saw fewer than tau pixels (paper 4.7.2)");
  cli.on_off("front-tracking", &c.front_tracking,
             "HC starts from the previous frame's fronts (paper 4.6) instead of the root");
}

void add_hc_options(Cli& cli, HcChoices& c) {
  cli.group(CliGroup::expert);
  cli.choice<std::optional<BackendKind>>(
      "backend", &c.backend, backend_words(),
      "how the OR draws depth and HC tests boxes against it: auto = cpu on a software renderer such as llvmpipe at "
      "tau 0 with the scene's triangles in memory, cpu-pyramid elsewhere there, queries on a hardware GPU (the "
      "start-up says which); cpu = a depth-only rasteriser on the CPU conservative against the renderer's depth, "
      "boxes and (tau 0) leaves by their own triangles tested there (not with --visible-pixel-lod or a scene "
      "streamed within --geometry-budget); queries = an occlusion query a box; gpu-pyramid = a depth pyramid built "
      "on the GPU first, queries for the rest; cpu-pyramid = the depth read back once a frame into a pyramid, the "
      "rest counted by one draw per batch. Same frames");
  cli.custom("coherence", "N|auto", "auto",
             "frames a node HC found visible stays in the visible set while in the frustum, and nodes whose queries "
             "keep coming back visible are assumed visible for a while (no query; with a depth pyramid still tested "
             "against it); 0 = neither; auto = 0 with --backend cpu, " + std::to_string(kAutoVisibilityHold) +
                 " elsewhere (the start-up says which)",
             [&c](const std::string& v) {
               if (v == "auto") {
                 c.adaptive_queries = std::nullopt;
                 c.visibility_hold = std::nullopt;
                 return;
               }
               const int n = int(Cli::whole("coherence", v, 0, 255, " or auto"));
               c.adaptive_queries = n > 0;
               c.visibility_hold = n;
             });
}

void add_listen_options(Cli& cli, ListenOptions& o) {
  cli.group(CliGroup::cluster);
  cli.option("listen", &o.listen, "ADDR:PORT", "where to listen (port 0 = pick a free one)");
  cli.option("port-file", &o.port_file, "FILE", "write the listening port here (atomically)");
}

net::Endpoint resolve_listen(const ListenOptions& o) { return net::parse_endpoint("listen", o.listen); }

net::Listener open_listener(const std::string& who, const ListenOptions& o) {
  const net::Endpoint at = net::parse_endpoint("listen", o.listen);
  auto listener = net::Listener::open(at.port, at.host);
  if (!listener) throw std::runtime_error(who + ": cannot listen on " + o.listen + ": " + listener.error());
  if (!o.port_file.empty())
    if (auto err = net::write_port_file(o.port_file, listener->port()))
      throw InputError("--port-file '" + o.port_file + "': " + *err);
  std::cerr << who << ": listening on " << listener->address() << ":" << listener->port() << "\n";
  return std::move(*listener);
}

void add_key_option(Cli& cli, std::string* file) {
  cli.group(CliGroup::cluster);
  cli.option("cluster-key-file", file, "FILE",
             "a secret shared by every process of the cluster (at least 32 bytes, e.g. `openssl rand -hex 32`): "
             "peers must prove it in the handshake (HMAC-SHA256); without it, anyone who can connect may join");
}

std::optional<net::ClusterKey> load_cluster_key(const std::string& file) {
  if (file.empty()) return std::nullopt;
  auto key = net::ClusterKey::load(file);
  if (!key) throw InputError("--cluster-key-file: " + key.error());
  return std::move(*key);
}

}  // namespace occ
