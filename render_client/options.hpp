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
  bool no_images = false;
  bool item_buffer = false;  // --item-buffer: DIR/items_%05d.png per frame (render_client/tools/item_diff.hpp)
  int width = 512, height = 512;
  GlBackend gl = GlBackend::Auto;
  // reference mode
  bool reference = false;
  Cull cull = Cull::frustum;
  bool exact = false;  // item-buffer pass per frame: exactly visible nodes
  std::string save_scene;  // write the loaded scene as glTF (ditto, generated scenes included)
  // cluster mode
  std::vector<std::string> connect;  // the two switch nodes
  int lookahead = 2;  // cameras sent ahead of the displayed frame (docs/latency.md: 2 = the paper's pipeline)
  int timeout_ms = 30000;
  bool degrade = true;  // --on-node-failure degrade|exit (node_links.hpp)
  OcclusionGate::Policy occlusion_gate = OcclusionGate::Policy::automatic;  // --occlusion-gate
  OcclusionGate::Policy two_pass = OcclusionGate::Policy::automatic;        // --two-pass (on/off/automatic)
  uint32_t test_alternate = 0;  // tests only (OCC_TEST_ALTERNATE, main.cpp): both gates alternate
  std::optional<net::ClusterKey> key;  // --cluster-key-file (docs/security.md)
  // --window or --web (viewer.hpp)
  bool window = false;
  std::string web;      // --web [ADDR:]PORT (web_server.hpp); empty: off
  std::string web_tls;  // --web-tls CERT.pem:KEY.pem|self-signed
  bool viewer() const { return window || !web.empty(); }  // a user watches and drives
  std::string record;  // every camera shown, as a path CSV
  std::string save_path;  // --save-path: the path (generated or read) as CSV (also for bench.sh's OSG rows)
};

int run_reference(const ClientOptions& o);
int run_cluster_client(const ClientOptions& o);

}  // namespace occ
