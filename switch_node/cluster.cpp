#include "switch_node/cluster.hpp"

#include "common/cli.hpp"
#include "common/error.hpp"
#include "common/hash.hpp"

namespace occ {

wire::Camera to_wire(uint32_t number, const Camera& c, const Viewport& vp) {
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
  return c;
}

wire::Hello make_hello(wire::Role role, uint8_t node_id, const Viewport& vp, uint64_t scene_fingerprint,
                       const BuildParams& build, const ClusterConfig& config, const std::string& name) {
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
  return h;
}

uint64_t ClusterConfig::hash() const {
  Hasher h;
  h.str(camera_mode);
  h.u32(full_sets);
  h.f64(pixel_error);
  h.str(visible_pixel_lod);
  h.str(front_tracking);
  return h.value();
}

void add_lod_options(Cli& cli, ClusterConfig& c) {
  cli.option("pixel-error", &c.pixel_error, 0.0, 1e6,
             "tau: screen-space error bound in pixels for LOD/HLOD selection (0 = original geometry, conservative)");
  cli.choice("visible-pixel-lod", &c.visible_pixel_lod, {"on", "off"},
             "stop refining a node whose occlusion query saw fewer than tau pixels (paper 4.7.2)");
  cli.choice("front-tracking", &c.front_tracking, {"on", "off"},
             "HC starts from the previous frame's fronts (paper 4.6) instead of the root");
}

Endpoint parse_endpoint(const std::string& flag, const std::string& text) {
  Endpoint e{"127.0.0.1", 0};
  std::string port = text;
  if (auto colon = text.rfind(':'); colon != std::string::npos) {
    e.host = text.substr(0, colon);
    port = text.substr(colon + 1);
    if (e.host.empty()) throw InputError("--" + flag + " '" + text + "': empty host");
  }
  size_t used = 0;
  long p = -1;
  try {
    p = std::stol(port, &used);
  } catch (...) {
    used = 0;
  }
  if (used == 0 || used != port.size() || p < 0 || p > 65535)
    throw InputError("--" + flag + " '" + text + "': expected HOST:PORT with PORT 0..65535");
  e.port = uint16_t(p);
  return e;
}

void add_listen_options(Cli& cli, ListenOptions& o) {
  cli.option("listen", &o.listen, "ADDR:PORT", "where to listen (port 0 = pick a free one)");
  cli.option("port", &o.port, -1, 65535,
             "listen on this port of the --listen address (0 = pick a free one, -1 = the port in --listen)");
  cli.option("port-file", &o.port_file, "FILE", "write the listening port here (atomically)");
}

Endpoint resolve_listen(ListenOptions& o) {
  Endpoint e = parse_endpoint("listen", o.listen);
  if (o.port >= 0) {
    e.port = uint16_t(o.port);
    o.listen = e.host + ":" + std::to_string(o.port);
  }
  return e;
}

}  // namespace occ
