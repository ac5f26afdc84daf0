// One switch node of the occlusion switch (paper 3.2, 4.2-4.4): alternately builds the
// occlusion representation (OR, depth only, from the visible set streamed by the other node)
// and performs hardware culling (HC, batched occlusion queries against that depth buffer),
// streaming the visible-set diff to the render client and to the other node. See cluster.hpp
// for the schedule.
#pragma once
#include <string>

#include "common/scene_setup.hpp"
#include "switch_node/cluster.hpp"

namespace occ {

struct NodeOptions {
  int id = 0;
  SceneOptions scene;
  ClusterConfig config;
  int width = 512, height = 512;
  std::string gl = "auto";
  std::string listen = "127.0.0.1:0";
  std::string port_file;
  std::string peer;  // node 1: where node 0 listens
  int diff_chunk_ids = 100;
  std::string adaptive_queries = "on";  // skip queries of nodes that keep coming back visible
  int timeout_ms = 30000;
};

// Returns the process exit code: 0 after the render client said Bye, 1 on a failure (printed
// as one "error:" line naming the frame and peer).
int run_switch_node(const NodeOptions& opts);

}  // namespace occ
