// render_client: the RVG display client of the occlusion switch, or (--reference) the
// single-process reference renderer.
#include <cstdlib>
#include <string>

#include "common/camera_path.hpp"

#include "common/cli.hpp"
#include "common/error.hpp"
#include "common/gl/startup.hpp"
#include "common/memory.hpp"
#include "render_client/options.hpp"
#include "render_client/web_server.hpp"

namespace {

// --occlusion-gate and --two-pass: auto, on or off.
void gate_option(occ::Cli& cli, const std::string& name, occ::OcclusionGate::Policy* out, const std::string& help) {
  using P = occ::OcclusionGate::Policy;
  cli.choice<P>(name, out, {{"auto", P::automatic}, {"on", P::on}, {"off", P::off}}, help);
}

// Tests only, not a user mode: OCC_TEST_ALTERNATE=N makes both gates take N frames each way in
// turn (OcclusionGate::Options::test_alternate), so a cluster test sees many changes of mode.
uint32_t test_alternate() {
  const char* v = std::getenv("OCC_TEST_ALTERNATE");
  if (!v || !*v) return 0;
  char* end = nullptr;
  const long n = std::strtol(v, &end, 10);
  if (*end || n < 1 || n > 1000) throw occ::InputError("OCC_TEST_ALTERNATE '" + std::string(v) + "': not 1..1000");
  return uint32_t(n);
}

}  // namespace

int main(int argc, char** argv) {
  occ::use_huge_pages(argv);
  return occ::run_main([&] {
    occ::ClientOptions o;
    occ::Cli cli("render_client",
                 "--connect HOST:PORT --connect HOST:PORT [options]\n       render_client --reference [options]",
                 "Drives the camera along a path, receives the visible set of every frame from the switch\n"
                 "node doing HC, verifies it, renders it and writes frames and statistics. With --reference\n"
                 "it renders the whole scene itself (no culling or frustum culling only): the ground truth.");
    cli.option("path", &o.path, "P",
               "camera path: file.csv, orbit:N, walk:N or fly:N (default walk:60), or interactive (--window, --web; "
               "their default)");
    cli.option("out", &o.out, "DIR", "write DIR/frame_%05d.png and DIR/stats.csv");
    cli.flag("no-images", &o.no_images, "write stats only (benchmarks)");
    cli.flag("item-buffer", &o.item_buffer,
             "also write DIR/items_%05d.png: each pixel the id of the item or HLOD that drew it (frame_diff --items)");
    occ::add_view_options(cli, o.scene, &o.width, &o.height, &o.gl);
    cli.flag("reference", &o.reference, "single-process reference renderer");
    cli.choice<occ::Cull>("cull", &o.cull,
                          {{"none", occ::Cull::none},
                           {"frustum", occ::Cull::frustum},
                           {"stop-and-wait", occ::Cull::stop_and_wait},
                           {"chc", occ::Cull::chc}},
                          "reference renderer: culling (stop-and-wait, chc: single-process occlusion queries)");
    cli.flag("exact", &o.exact, "reference renderer: also count exactly visible nodes (item buffer)");
    cli.option("save-scene", &o.save_scene, "FILE.gltf",
               "reference renderer: also write the scene as glTF (FILE.gltf + FILE.bin, geometry only)");
    cli.multi("connect", &o.connect, "HOST:PORT", "a switch node (give both, any order) or one occlusion_server");
    occ::add_cluster_options(cli, o.config);
    cli.option("lookahead", &o.lookahead, 1, 64,
               "cameras sent ahead of the displayed frame (lockstep: the latency in frames; latest: the most frames "
               "in flight)");
    cli.option("timeout-ms", &o.timeout_ms, 100, 3600000, "longest wait for a node or a message");
    gate_option(cli, "occlusion-gate", &o.occlusion_gate,
                "occlusion only where it pays: auto = frames without occlusion (the switch sends frustum sets: no OR, "
                "no queries) while they are measured faster at the display (each frame against its frustum set's "
                "triangles, so a path that gets lighter or heavier does not decide), tried where culling removes "
                "little; on = "
                "always occlusion; off = never");
    gate_option(cli, "two-pass", &o.two_pass,
                "frames of frustum sets (the switch culled without occlusion, or no node serves) culled here: drawn in "
                "two passes, first what showed last time, then what that depth does not prove hidden (one depth "
                "read-back; exact). auto = one pass first, two where measured faster (tried after a window of one, "
                "not while the occlusion gate measures frames without occlusion; off on a hardware GPU, where the "
                "read-back stalls it); on; off");
    cli.choice<bool>("on-node-failure", &o.degrade, {{"degrade", true}, {"exit", false}},
                     "a switch node dies, stalls past --timeout-ms or sends something invalid: degrade (go on "
                     "with the other node alone or frustum culling here, and take the node back when it is "
                     "restarted) or exit (status 1, naming node and frame: benchmarks)");
    std::string key_file;
    occ::add_key_option(cli, &key_file);
    cli.flag("window", &o.window,
             "show the frames in an X11 window ($DISPLAY) and let the user drive: W/A/S/D/Q/E move, arrows or "
             "drag look, Shift faster, wheel speed, F walk/fly, R reset, P screenshot to --out, O culling overlay (occlusion-culled boxes tinted), Esc quits");
    cli.option("web", &o.web, "[ADDR:]PORT",
               "serve a page that shows the frames and lets the user drive as --window does (mouse, wheel, keys, "
               "touch): http://ADDR:PORT/ (ADDR default 127.0.0.1; PORT 0: a free one); the drive and view-only URLs, "
               "with their tokens, are printed at start");
    cli.option("web-tls", &o.web_tls, "CERT:KEY",
               "--web over https/wss: CERT.pem:KEY.pem (a PEM certificate chain and its key), or self-signed (a fresh "
               "pair for localhost made at start, its fingerprint printed)");
    cli.option("record", &o.record, "FILE.csv", "--window/--web: write every camera shown as a --path CSV (replays the flight)");
    cli.option("save-path", &o.save_path, "FILE.csv", "write the camera path (e.g. a generated walk:N) as a --path CSV");
    if (!cli.parse(argc, argv)) return 0;
    if (o.window && !o.web.empty()) throw occ::InputError("--web: not with --window (one display)");
    if (!o.web_tls.empty() && o.web.empty()) throw occ::InputError("--web-tls needs --web");
    if (!o.web.empty()) occ::parse_web_options(o.web, o.web_tls);  // a bad --web fails before the scene loads
    if (!o.save_path.empty() && o.viewer()) throw occ::InputError("--save-path: with --window or --web, use --record");
    if (o.path.empty()) o.path = o.viewer() ? "interactive" : "walk:60";
    if (o.path == "interactive" && !o.viewer()) throw occ::InputError("--path interactive needs --window or --web");
    if (!o.record.empty() && !o.viewer()) throw occ::InputError("--record needs --window or --web");
    if (o.path != "interactive") {  // a bad --path fails now, not after the scene has loaded
      occ::Aabb unit;
      unit.grow(glm::dvec3(0.0));
      unit.grow(glm::dvec3(1.0));
      occ::load_camera_path(o.path, unit, {o.width, o.height});
    }
    if (o.reference) {
      if (!o.connect.empty()) throw occ::InputError("--connect makes no sense with --reference");
      if (!key_file.empty()) throw occ::InputError("--cluster-key-file makes no sense with --reference");
      return occ::run_reference(o);
    }
    if (o.connect.empty() || o.connect.size() > 2)
      throw occ::InputError(
          "give --connect twice (both switch nodes), once (an occlusion_server), or --reference (see render_client "
          "--help)");
    for (const auto& c : o.connect) occ::net::parse_endpoint("connect", c);  // fail before loading the scene
    o.key = occ::load_cluster_key(key_file);
    o.test_alternate = test_alternate();
    return occ::run_cluster_client(o);
  });
}
