// render_client's settings, shared by its two modes: the reference renderer (single process,
// no culling or frustum culling: the ground truth every cluster frame is compared with) and the
// RVG display client of the cluster.
#pragma once
#include <optional>
#include <string>
#include <vector>

#include "common/gl/context.hpp"
#include "common/cull/occlusion_gate.hpp"
#include "common/setup/scene_setup.hpp"
#include "protocol/cluster/cluster.hpp"

namespace occ {

// --cull of the reference renderer: no culling, hierarchical frustum culling, or a single-process
// occlusion baseline (render_client/baselines/single_process.hpp).
enum class Cull { none, frustum, stop_and_wait, chc };
const char* cull_name(Cull c);  // its --cull word

struct ClientOptions {
  SceneOptions scene;
  ClusterConfig config;
  std::string path;  // empty: walk:60, or interactive with --window (main.cpp)
  std::string out;
  bool no_images = false;    // --images off
  bool item_buffer = false;  // --images items: DIR/items_%05d.png per frame (render_client/tools/item_diff.hpp)
  int width = 512, height = 512;
  GlBackend gl = GlBackend::Auto;
  // reference mode (no --connect)
  Cull cull = Cull::frustum;
  bool exact = false;  // item-buffer pass per frame: exactly visible nodes
  // cluster mode
  std::vector<std::string> connect;  // the two switch nodes
  int lookahead = 2;  // cameras sent ahead of the displayed frame (docs/latency.md: 2 = the paper's pipeline)
  int timeout_ms = 30000;
  bool degrade = true;  // --on-node-failure degrade|exit (node_links.hpp)
  // --occlusion (main.cpp) sets both gates: the switch's and this process's two passes.
  OcclusionGate::Policy occlusion_gate = OcclusionGate::Policy::automatic;
  OcclusionGate::Policy two_pass = OcclusionGate::Policy::automatic;
  uint32_t alternate_every = 4;  // Policy::alternate (--occlusion alternate:N)
  std::optional<net::ClusterKey> key;  // --cluster-key-file (docs/security.md)
  // --window or --web (viewer.hpp)
  bool window = false;
  std::string web;      // --web [ADDR:]PORT (web_server.hpp); empty: off
  std::string web_tls;  // --web's tls= CERT.pem:KEY.pem|self-signed
  bool viewer() const { return window || !web.empty(); }  // a user watches and drives
  // OUT/path.csv with --out (main.cpp): every camera shown (--window, --web), or the path
  // (generated or read), as a path CSV
  std::string record;
};

int run_reference(const ClientOptions& o);
int run_cluster_client(const ClientOptions& o);

}  // namespace occ
