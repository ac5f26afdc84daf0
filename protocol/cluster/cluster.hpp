// What the three cluster processes share beyond the wire format: the camera conversion, the
// settings that must agree (config hash in Hello), the switch schedule, and the listening flags.
//
// Schedule (paper 3.2 and Algorithm 4.2; README "Architecture"). Frame f: node f % 2 performs HC(f) and
// streams V_f as a diff against V_{f-1}; node (f+1) % 2 builds OR(f+1) from that stream. So
// node k runs OR(k), HC(k), OR(k+2), HC(k+2), ... OR(f+1) draws V_{f-1} (which it holds) at
// once and each added node as it arrives: the depth of any subset of real geometry is
// conservative, and V_{f-1} ∪ δ+ = V_{f-1} ∪ V_f occludes at least as much as V_f.
#pragma once
#include <cstdint>
#include <optional>
#include <string>

#include "common/camera.hpp"
#include "common/cull/culling.hpp"
#include "common/scene/hierarchy.hpp"
#include "protocol/net/auth.hpp"
#include "protocol/net/endpoint.hpp"
#include "protocol/net/transport.hpp"
#include "protocol/wire.hpp"

namespace occ {

class Cli;

// `occlusion`: whether the switch culls this camera's frame with occlusion (wire.hpp Camera: 0
// without, 1 with).
wire::Camera to_wire(uint32_t number, const Camera& c, const Viewport& vp, uint8_t occlusion = 1);
Camera from_wire(const wire::Camera& w);
// Why a camera packet does not fit a process rendering `vp` (nullopt when it does).
std::optional<std::string> viewport_mismatch(const wire::Camera& w, const Viewport& vp);

enum class CameraMode {
  lockstep,  // frame f uses camera f (reproducible)
  latest,    // the OR node takes the newest camera (the paper's interactive system)
};
const char* camera_mode_name(CameraMode m);

// Settings that must agree on all three processes (they are in hash(), checked in the hello).
struct ClusterConfig {
  CameraMode camera_mode = CameraMode::lockstep;
  double pixel_error = 0;          // tau, the paper's pixels of error (0 = original geometry)
  bool visible_pixel_lod = false;  // stop refining where fewer than tau pixels show (4.7.2)
  bool front_tracking = true;      // HC starts from the fronts (4.6) or the root

  bool lod() const { return pixel_error > 0; }  // LODs are loaded/built only when used
  LodPolicy lod_policy(int viewport_height_px) const {
    return {pixel_error, double(viewport_height_px), visible_pixel_lod};
  }
  uint64_t hash() const;
};

// The one HC option set (common/cull/culling.hpp HcChoices), from the command line: --backend,
// --coherence (adaptive queries and the visibility hold together; occluder fusion and the sealed
// solids are always on).
void add_hc_options(Cli& cli, HcChoices& c);

// The Hello every process sends: who it is and everything that must agree between processes.
// `occlusion_backend`: a switch node's back end as its start-up line names it (wire.hpp's rules:
// lower-case letters, digits, '-'); "" for the render client and tools.
wire::Hello make_hello(wire::Role role, uint8_t node_id, const Viewport& vp, uint64_t scene_fingerprint,
                       const BuildParams& build, const ClusterConfig& config, const std::string& name,
                       const std::string& occlusion_backend);

// --camera-mode, --pixel-error, --visible-pixel-lod, --front-tracking.
void add_cluster_options(Cli& cli, ClusterConfig& c);

// Where a listening process listens: --listen ADDR:PORT (port 0: a free one), --port-file FILE.
// resolve_listen() checks the address after parsing.
struct ListenOptions {
  std::string listen = "127.0.0.1:0";
  std::string port_file;
};
void add_listen_options(Cli& cli, ListenOptions& o);
net::Endpoint resolve_listen(const ListenOptions& o);
// Opens the listening socket (after resolve_listen), writes --port-file and prints
// "<who>: listening on ADDR:PORT". Throws naming the address.
net::Listener open_listener(const std::string& who, const ListenOptions& o);

// --cluster-key-file FILE: membership by a shared key (docs/security.md), on every process.
void add_key_option(Cli& cli, std::string* file);
// The key of --cluster-key-file, or none when no file was given. Throws InputError naming the
// file when it is missing, unreadable, empty or too short.
std::optional<net::ClusterKey> load_cluster_key(const std::string& file);

inline uint32_t hc_node_of_frame(uint32_t frame) { return frame % 2; }

}  // namespace occ
