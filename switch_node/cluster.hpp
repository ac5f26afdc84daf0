// What the three cluster processes share beyond the wire format: the camera conversion, the
// settings that must agree (config hash in Hello), the switch schedule, and endpoint parsing.
//
// Schedule (paper 3.2 and Algorithm 4.2, README.md intro). Frame f: node f % 2 performs HC(f) and
// streams V_f as a diff against V_{f-1}; node (f+1) % 2 builds OR(f+1) from that stream. So
// node k runs OR(k), HC(k), OR(k+2), HC(k+2), ... OR(f+1) draws V_{f-1} (which it holds) at
// once and each added node as it arrives: the depth of any subset of real geometry is
// conservative, and V_{f-1} ∪ δ+ = V_{f-1} ∪ V_f occludes at least as much as V_f.
#pragma once
#include <cstdint>
#include <string>

#include "common/camera.hpp"
#include "common/cli.hpp"
#include "common/hierarchy.hpp"
#include "protocol/wire.hpp"

namespace occ {

wire::Camera to_wire(uint32_t number, const Camera& c, const Viewport& vp);
Camera from_wire(const wire::Camera& w);

struct ClusterConfig {
  std::string camera_mode = "lockstep";  // lockstep | latest
  bool full_sets = false;                // send all of V_f each frame instead of the diff
  double pixel_error = 0;                // tau, the paper's pixels of error (0 = original geometry)
  std::string visible_pixel_lod = "off"; // on | off: stop refining where fewer than tau pixels show
  std::string front_tracking = "on";     // on | off: HC starts from the fronts (4.6) or the root
  bool lod() const { return pixel_error > 0; }  // LODs are loaded/built only when used
  uint64_t hash() const;
};

// The Hello every process sends: who it is and everything that must agree between processes.
wire::Hello make_hello(wire::Role role, uint8_t node_id, const Viewport& vp, uint64_t scene_fingerprint,
                       const BuildParams& build, const ClusterConfig& config, const std::string& name);

class Cli;
// --pixel-error, --visible-pixel-lod, --front-tracking (all must agree: they are in hash()).
void add_lod_options(Cli& cli, ClusterConfig& c);

struct Endpoint {
  std::string host;
  uint16_t port = 0;
};
// "HOST:PORT" or "PORT" (host 127.0.0.1); throws InputError naming the flag.
Endpoint parse_endpoint(const std::string& flag, const std::string& text);

// Where a listening process listens: --listen ADDR:PORT, --port N (the port of that address;
// shorthand for the common --port 0 --port-file F), --port-file FILE. After parsing,
// resolve_listen() folds --port into the listen string and checks it.
struct ListenOptions {
  std::string listen = "127.0.0.1:0";
  int port = -1;  // -1: --listen's port
  std::string port_file;
};
void add_listen_options(Cli& cli, ListenOptions& o);
Endpoint resolve_listen(ListenOptions& o);

inline uint32_t hc_node_of_frame(uint32_t frame) { return frame % 2; }

}  // namespace occ
