// occlusion_server: the depth-readback baseline the paper calls "Distributed GigaWalk" (section
// 5). One process does both halves every frame: it renders the occluders (the previous visible
// set, depth only) for the new camera, reads the depth buffer back, builds a software
// hierarchical Z pyramid and tests the hierarchy's boxes against it on the CPU (the same
// breadth-first traversal as HC, with the pyramid answering instead of GL queries). The display
// client is the ordinary render_client with a single --connect. Lockstep cameras only.
#include <chrono>
#include <iostream>
#include <thread>

#include "common/camera_buffer.hpp"
#include "common/cli.hpp"
#include "common/cpu_time.hpp"
#include "common/cull/culling.hpp"
#include "common/error.hpp"
#include "common/gl/context.hpp"
#include "common/gl/scene_renderer.hpp"
#include "common/gl/startup.hpp"
#include "common/cull/hzb.hpp"
#include "common/memory.hpp"
#include "common/setup/scene_setup.hpp"
#include "protocol/cluster/camera_receiver.hpp"
#include "protocol/cluster/cluster.hpp"
#include "protocol/cluster/switch_step.hpp"
#include "protocol/net/transport.hpp"
#include "protocol/visible_set.hpp"

namespace occ {
namespace {

using Clock = std::chrono::steady_clock;

uint32_t micros_since(Clock::time_point t0) {
  return uint32_t(std::chrono::duration_cast<std::chrono::microseconds>(Clock::now() - t0).count());
}

// The pyramid as an OcclusionQueries: "samples" are 1 when the box may be visible.
class PyramidQueries : public OcclusionQueries {
 public:
  PyramidQueries(const DepthPyramid& p, const Camera& cam) : p_(p), cam_(cam) {}
  uint32_t issue(const Aabb& box) override {
    results_.push_back(p_.may_be_visible(box, cam_));
    return uint32_t(results_.size() - 1);
  }
  uint64_t result(uint32_t h) override { return results_.at(h); }
  void end_batch() override { results_.clear(); }

 private:
  const DepthPyramid& p_;
  const Camera& cam_;
  std::vector<uint8_t> results_;
};

struct ServerOptions {
  SceneOptions scene;
  int width = 512, height = 512;
  GlBackend gl = GlBackend::Auto;
  ListenOptions listen;
  int timeout_ms = 30000;
  std::optional<net::ClusterKey> key;  // --cluster-key-file
};

int serve(const ServerOptions& o) {
  const std::string who = "occlusion_server";
  SceneGl g = start_scene_gl(who, o.scene, false, o.gl, o.width, o.height);
  const Hierarchy& h = g.hierarchy();
  g.renderer->set_occluder_offset(true);  // occluders must not hide their own boxes from the pyramid

  net::Listener listener = open_listener(who, o.listen);
  const ClusterConfig config;  // lockstep, incremental: what the render client expects by default
  const wire::Hello mine =
      make_hello(wire::Role::switch_node, 0, {o.width, o.height}, g.fingerprint(), h.params(), config, who, "depth-readback");
  net::PeerExpectation expect{wire::Role::render_client, std::nullopt};
  expect.key = o.key ? &*o.key : nullptr;
  auto peer = listener.accept_peer(mine, expect, net::Millis(o.timeout_ms), net::Millis(2000), net::keyed_options(expect.key));
  if (!peer) throw std::runtime_error("no render client: " + peer.error());
  net::Connection& rvg = peer->connection;

  CameraBuffer cameras;
  CameraReceiver cameras_in(rvg, cameras, {o.width, o.height});
  VisibleSet visible(uint32_t(h.size()));
  // The switch's step without LODs or fronts: one server does every frame from the root.
  const SwitchStep step(*g.renderables, LodPolicy{}, false);
  DiffSender out(wire::kDefaultDiffChunkIds, [&](const wire::Message& m) {
    if (auto err = rvg.send(m)) throw std::runtime_error("sending to the render client: " + *err);
  });
  DepthPyramid pyramid;
  int code = 0;
  try {
    for (uint32_t frame = 0;; ++frame) {
      std::string why;
      auto cam = cameras.take(frame, net::Millis(o.timeout_ms), &why);
      if (!cam) {
        if (cameras_in.client_said_bye()) break;
        throw std::runtime_error("frame " + std::to_string(frame) + ": " + why);
      }
      // Occluders: the previous visible set, depth only, then readback and the pyramid.
      const Clock::time_point or_start = Clock::now();
      const uint64_t or_cpu0 = process_cpu_us();
      g.renderer->begin_frame(cam->camera, false);
      std::vector<uint32_t> prev(visible.ids().begin(), visible.ids().end());
      g.renderer->draw_items(items_of_nodes(h, prev), SceneRenderer::Mode::DepthOnly);
      pyramid.build(g.ctx->read_depth(), o.width, o.height);
      const uint32_t or_us = micros_since(or_start);
      const uint64_t hc_cpu0 = process_cpu_us();
      // Culling on the CPU, streamed like HC.
      out.send(to_wire(cam->number, cam->camera, {o.width, o.height}));
      const Clock::time_point hc_start = Clock::now();
      PyramidQueries queries(pyramid, cam->camera);
      // Breadth-first levels (the paper's 4.7.1), no adaptive queries, no fusion: its own traversal.
      HcFrame hc = step.hc(frame, visible, cam->camera, queries,
                           {.choices = {.occluder_fusion = false},
                            .first_batch = HcOptions::kWholeFrontier,
                            .max_batch = HcOptions::kWholeFrontier},
                           out);
      hc.eof.or_us = or_us;
      hc.eof.hc_us = micros_since(hc_start);
      hc.eof.hc_cpu_us = uint32_t(process_cpu_us() - hc_cpu0);
      hc.eof.or_cpu_us = uint32_t(hc_cpu0 - or_cpu0);  // render, readback and pyramid
      out.send(hc.eof);
    }
  } catch (const std::exception& e) {
    if (!cameras_in.client_said_bye()) {
      std::cerr << "error: " << who << ": " << e.what() << "\n";
      rvg.close_with_error(who + " failed: " + e.what());
      code = 1;
    }
  }
  if (code == 0) rvg.close(wire::kByeDone);
  cameras_in.join();
  std::cerr << who << ": summary: peak_rss_mb=" << peak_rss_mb() << "\n";
  return code;
}

}  // namespace
}  // namespace occ

int main(int argc, char** argv) {
  occ::use_huge_pages(argv);
  return occ::run_main([&] {
    occ::ServerOptions o;
    occ::Cli cli("occlusion_server", "[options]",
                 "Depth-readback occlusion server (the paper's \"Distributed GigaWalk\" baseline): renders the\n"
                 "previous visible set depth-only, reads the depth back, builds a software hierarchical Z\n"
                 "pyramid and culls the hierarchy on the CPU; a render_client with one --connect displays.");
    occ::add_view_options(cli, o.scene, &o.width, &o.height, &o.gl, "must match the render client");
    occ::add_listen_options(cli, o.listen);
    cli.option("timeout-ms", &o.timeout_ms, 100, 3600000, "longest wait for the client or a camera");
    std::string key_file;
    occ::add_key_option(cli, &key_file);
    if (!cli.parse(argc, argv)) return 0;
    occ::resolve_listen(o.listen);  // fail before loading the scene
    o.key = occ::load_cluster_key(key_file);
    return occ::serve(o);
  });
}
