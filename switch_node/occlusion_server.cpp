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
#include "common/culling.hpp"
#include "common/error.hpp"
#include "common/gl/context.hpp"
#include "common/gl/scene_renderer.hpp"
#include "common/hzb.hpp"
#include "common/scene_setup.hpp"
#include "protocol/net/transport.hpp"
#include "protocol/visible_set.hpp"
#include "switch_node/cluster.hpp"

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
  std::string gl = "auto", listen = "127.0.0.1:0", port_file;
  int diff_chunk_ids = 100, timeout_ms = 30000;
};

int serve(const ServerOptions& o) {
  const std::string who = "occlusion_server";
  LoadedScene ls = load_and_build(o.scene, who);
  const Hierarchy& h = ls.hierarchy;
  auto ctx = GlContext::create(parse_gl_backend(o.gl), o.width, o.height);
  std::cerr << who << ": GL_RENDERER " << ctx->renderer() << " (" << ctx->backend_name() << ")\n";
  SceneRenderer renderer(*ctx, ls.scene, h);
  renderer.set_occluder_offset(true);  // occluders must not hide their own boxes from the pyramid

  Endpoint listen = parse_endpoint("listen", o.listen);
  auto listener = net::Listener::open(listen.port, listen.host);
  if (!listener) throw std::runtime_error("cannot listen on " + o.listen + ": " + listener.error());
  if (!o.port_file.empty())
    if (auto err = net::write_port_file(o.port_file, listener->port())) throw InputError("--port-file: " + *err);
  ClusterConfig config;  // lockstep, incremental
  const wire::Hello mine =
      make_hello(wire::Role::switch_node, 0, {o.width, o.height}, ls.fingerprint, h.params(), config, who);
  auto peer = listener->accept_peer(mine, {wire::Role::render_client, std::nullopt}, net::Millis(o.timeout_ms));
  if (!peer) throw std::runtime_error("no render client: " + peer.error());
  net::Connection& rvg = peer->connection;

  CameraBuffer cameras;
  std::atomic<bool> bye{false};
  std::thread receiver([&] {
    for (;;) {
      net::Received r = rvg.receive(net::Millis(1000));
      if (r.status == net::Received::Status::timeout) continue;
      if (r.ok()) {
        if (auto* c = std::get_if<wire::Camera>(&r.message)) {
          cameras.put({c->frame, from_wire(*c)});
          continue;
        }
        cameras.close("unexpected message from the render client");
        return;
      }
      bye = r.status == net::Received::Status::closed;
      cameras.close(r.reason);
      return;
    }
  });

  auto send = [&](const wire::Message& m) {
    if (auto err = rvg.send(m)) throw std::runtime_error("sending to the render client: " + *err);
  };
  VisibleSet visible(uint32_t(h.size()));
  const Renderables renderables(h, nullptr);
  DepthPyramid pyramid;
  int code = 0;
  try {
    for (uint32_t frame = 0;; ++frame) {
      std::string why;
      auto cam = cameras.take(frame, net::Millis(o.timeout_ms), &why);
      if (!cam) {
        if (bye) break;
        throw std::runtime_error("frame " + std::to_string(frame) + ": " + why);
      }
      // Occluders: the previous visible set, depth only, then readback and the pyramid.
      const Clock::time_point or_start = Clock::now();
      const uint64_t or_cpu0 = process_cpu_us();
      renderer.begin_frame(cam->camera, false);
      std::vector<uint32_t> prev(visible.ids().begin(), visible.ids().end());
      renderer.draw_items(items_of_nodes(h, prev), SceneRenderer::Mode::DepthOnly);
      pyramid.build(ctx->read_depth(), o.width, o.height);
      const uint32_t or_us = micros_since(or_start);
      const uint64_t hc_cpu0 = process_cpu_us();
      // Culling on the CPU, streamed like HC.
      send(to_wire(cam->number, cam->camera, {o.width, o.height}));
      const Clock::time_point hc_start = Clock::now();
      PyramidQueries queries(pyramid, cam->camera);
      CullStats stats;
      SetDiff diff;
      std::vector<uint32_t> pending;
      std::vector<uint32_t> leaves = hardware_cull(
          renderables, cam->camera, queries,
          [&](uint32_t id) {
            if (visible.contains(id)) return;
            diff.added.push_back(id);
            pending.push_back(id);
            if (pending.size() >= size_t(o.diff_chunk_ids)) {
              send(wire::NodeDiff{frame, pending, {}});
              pending.clear();
            }
          },
          &stats);
      if (!pending.empty()) send(wire::NodeDiff{frame, pending, {}});
      VisibleSet cur(uint32_t(h.size()));
      for (uint32_t id : leaves) cur.insert(id);
      for (uint32_t id : visible.ids())
        if (!cur.contains(id)) diff.removed.push_back(id);
      for (auto& chunk : wire::chunk_node_diff(frame, {}, diff.removed, uint32_t(o.diff_chunk_ids))) send(chunk);
      wire::EndOfFrame eof = make_end_of_frame(frame, diff, cur);
      eof.queries = stats.queries;  // boxes tested against the pyramid
      eof.or_us = or_us;
      eof.hc_us = micros_since(hc_start);
      eof.hc_cpu_us = uint32_t(process_cpu_us() - hc_cpu0);
      eof.or_cpu_us = uint32_t(hc_cpu0 - or_cpu0);  // render, readback and pyramid
      for (uint32_t id : leaves) eof.triangles += h.node(id).triangles;
      send(eof);
      visible = std::move(cur);
    }
  } catch (const std::exception& e) {
    if (!bye) {
      std::cerr << "error: " << who << ": " << e.what() << "\n";
      rvg.close_with_error(who + " failed: " + e.what());
      code = 1;
    }
  }
  if (code == 0) rvg.close(wire::kByeDone);
  receiver.join();
  return code;
}

}  // namespace
}  // namespace occ

int main(int argc, char** argv) {
  return occ::run_main([&] {
    occ::ServerOptions o;
    occ::Cli cli("occlusion_server", "[options]",
                 "Depth-readback occlusion server (the paper's \"Distributed GigaWalk\" baseline): renders the\n"
                 "previous visible set depth-only, reads the depth back, builds a software hierarchical Z\n"
                 "pyramid and culls the hierarchy on the CPU; a render_client with one --connect displays.");
    occ::add_scene_options(cli, o.scene);
    cli.option("width", &o.width, 16, occ::kMaxViewportPx, "viewport width (must match the render client)");
    cli.option("height", &o.height, 16, occ::kMaxViewportPx, "viewport height");
    cli.choice("gl", &o.gl, {"auto", "egl", "osmesa"}, "GL back end");
    occ::ListenOptions where;
    occ::add_listen_options(cli, where);
    cli.option("diff-chunk", &o.diff_chunk_ids, 1, 100000, "node ids per diff message");
    cli.option("timeout-ms", &o.timeout_ms, 100, 3600000, "longest wait for the client or a camera");
    if (!cli.parse(argc, argv)) return 0;
    occ::resolve_listen(where);  // fail before loading the scene
    o.listen = where.listen;
    o.port_file = where.port_file;
    return occ::serve(o);
  });
}
