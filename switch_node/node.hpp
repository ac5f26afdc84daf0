// One switch node of the occlusion switch (paper 3.2, 4.2-4.4): alternately builds the
// occlusion representation (OR, depth only, from the visible set streamed by the other node)
// and performs hardware culling (HC, batched occlusion queries against that depth buffer),
// streaming the visible-set diff to the render client and to the other node. The schedule is in
// protocol/cluster/cluster.hpp, the per-frame logic in protocol/cluster/switch_step.hpp.
#pragma once
#include <optional>
#include <string>

#include "common/gl/context.hpp"
#include "common/setup/scene_setup.hpp"
#include "protocol/cluster/cluster.hpp"

namespace occ {

struct NodeOptions {
  int id = 0;
  SceneOptions scene;
  ClusterConfig config;
  int width = 512, height = 512;
  GlBackend gl = GlBackend::Auto;
  ListenOptions listen;
  std::string peer;  // node 1: where node 0 listens
  HcChoices hc;
  int timeout_ms = 30000;
  std::optional<net::ClusterKey> key;  // --cluster-key-file (docs/security.md)
  bool serve = false;                  // --serve: one render client after the other
  int sessions = 0;                    // --serve N: exit after N clients (0, forever: never)
};

// Returns the process exit code: 0 after the render client said Bye, 1 on a failure (printed
// as one "error:" line naming the frame and peer). With serve, it returns only after `sessions`
// clients (0 if every one of them ended with its Bye), or never.
int run_switch_node(const NodeOptions& opts);

}  // namespace occ
