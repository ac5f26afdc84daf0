// render_client: the RVG display client of the occlusion switch, or (without --connect) the
// single-process reference renderer.
#include <filesystem>
#include <string>
#include <system_error>
#include <tuple>
#include <utility>

#include "common/camera_path.hpp"

#include "common/cli.hpp"
#include "common/error.hpp"
#include "common/gl/startup.hpp"
#include "common/memory.hpp"
#include "render_client/options.hpp"
#include "render_client/web_server.hpp"

namespace {

using Policy = occ::OcclusionGate::Policy;

// --occlusion: where the frames are culled with occlusion; sets both gates (the switch's,
// OcclusionGate, and the render client's own two passes for frustum sets, FrameDrawer).
void occlusion_option(occ::Cli& cli, occ::ClientOptions& o) {
  cli.custom(
      "occlusion", "auto|switch|client|frustum|alternate:N", "auto",
      "where frames are culled with occlusion: auto = where it pays (frames without it at the switch, its "
      "frustum sets culled here in two passes against their own depth where that is measured faster; tried "
      "where occlusion culls little; two passes off on a hardware GPU, where the read-back stalls it); switch = "
      "every frame by the switch (as designed); client = the switch sends frustum sets (no OR, no box tests), "
      "this process culls them in two passes; frustum = frustum culling only; alternate:N = N cameras each of "
      "switch and of frustum sets in turn, those in turn N in two passes and N in one (every method on one "
      "path: stats.csv's occlusion and two_pass columns say which). Same frames",
      [&o](const std::string& v) {
        const std::pair<const char*, std::pair<Policy, Policy>> words[] = {
            {"auto", {Policy::automatic, Policy::automatic}},
            {"switch", {Policy::on, Policy::automatic}},
            {"client", {Policy::off, Policy::on}},
            {"frustum", {Policy::off, Policy::off}}};
        for (const auto& [w, p] : words)
          if (v == w) {
            std::tie(o.occlusion_gate, o.two_pass) = p;
            return;
          }
        if (v.rfind("alternate:", 0) != 0)
          throw occ::InputError("--occlusion '" + v + "': expected auto, switch, client, frustum or alternate:N");
        o.occlusion_gate = o.two_pass = Policy::alternate;
        o.alternate_every = uint32_t(occ::Cli::whole("occlusion", v.substr(10), 1, 1000));
      });
}

// --images png|items|png+items|off.
void images_option(occ::Cli& cli, occ::ClientOptions& o) {
  cli.custom("images", "png|items|png+items|off", "png",
             "with --out: png = DIR/frame_%05d.png a frame; items = DIR/items_%05d.png instead, each pixel the id of "
             "the item or HLOD that drew it (frame_diff --items); png+items = both; off = neither (benchmarks)",
             [&o](const std::string& v) {
               if (v != "png" && v != "items" && v != "png+items" && v != "off")
                 throw occ::InputError("--images '" + v + "': expected png, items, png+items or off");
               o.no_images = v == "off" || v == "items";
               o.item_buffer = v == "items" || v == "png+items";
             });
}

}  // namespace

int main(int argc, char** argv) {
  occ::use_huge_pages(argv);
  return occ::run_main([&] {
    occ::ClientOptions o;
    occ::Cli cli("render_client", "--connect HOST:PORT --connect HOST:PORT [options]\n       render_client [options]",
                 "Drives the camera along a path, receives the visible set of every frame from the switch\n"
                 "node doing HC, verifies it, renders it and writes frames and statistics. Without --connect\n"
                 "it renders the scene itself (the reference renderer: --cull says how): the ground truth.");
    cli.group(occ::CliGroup::scene);
    cli.option("path", &o.path, "P",
               "camera path: file.csv, orbit:N, walk:N or fly:N (default walk:60), or interactive (--window, --web; "
               "their default)");
    occ::add_view_options(cli, o.scene, &o.width, &o.height, &o.gl);
    cli.group(occ::CliGroup::output);
    cli.option("out", &o.out, "DIR",
               "write DIR/frame_%05d.png, DIR/stats.csv and DIR/path.csv (the cameras shown as a --path CSV: the "
               "path, e.g. a generated walk:N, or with --window the flight the user flew)");
    images_option(cli, o);
    cli.flag("window", &o.window,
             "show the frames in an X11 window ($DISPLAY) and let the user drive: W/A/S/D/Q/E move, arrows or "
             "drag look, Shift faster, wheel speed, F walk/fly, R reset, P screenshot to --out, O culling overlay "
             "(occlusion-culled boxes tinted), Esc quits");
    cli.group(occ::CliGroup::cluster);
    cli.multi("connect", &o.connect, "HOST:PORT",
              "a switch node (give both, any order) or one occlusion_server; without it, the reference renderer");
    occ::add_cluster_options(cli, o.config);
    cli.group(occ::CliGroup::cluster);
    cli.option("timeout-ms", &o.timeout_ms, 100, 3600000, "longest wait for a node or a message");
    cli.choice<bool>("on-node-failure", &o.degrade, {{"degrade", true}, {"exit", false}},
                     "a switch node dies, stalls past --timeout-ms or sends something invalid: degrade (go on "
                     "with the other node alone or frustum culling here, and take the node back when it is "
                     "restarted) or exit (status 1, naming node and frame: benchmarks)");
    std::string key_file;
    occ::add_key_option(cli, &key_file);
    cli.group(occ::CliGroup::accuracy);
    cli.choice<occ::Cull>("cull", &o.cull,
                          {{"none", occ::Cull::none},
                           {"frustum", occ::Cull::frustum},
                           {"stop-and-wait", occ::Cull::stop_and_wait},
                           {"chc", occ::Cull::chc}},
                          "reference renderer (no --connect): culling (stop-and-wait, chc: single-process occlusion "
                          "queries)");
    cli.flag("exact", &o.exact, "reference renderer: also count exactly visible nodes (item buffer)");
    cli.group(occ::CliGroup::expert);
    occlusion_option(cli, o);
    cli.group(occ::CliGroup::output);
    cli.custom("web", "[ADDR:]PORT[,tls=CERT.pem:KEY.pem|,tls=self-signed]", "",
               "serve a page that shows the frames and lets the user drive as --window does (mouse, wheel, keys, "
               "touch): http://ADDR:PORT/ (ADDR default 127.0.0.1; PORT 0: a free one); the drive and view-only URLs, "
               "with their tokens, are printed at start. ,tls=: https/wss with a PEM certificate chain and its key, "
               "or self-signed (a fresh pair for localhost made at start, its fingerprint printed)",
               [&o](const std::string& v) {
                 const size_t at = v.find(",tls=");
                 o.web = v.substr(0, at);
                 o.web_tls = at == std::string::npos ? "" : v.substr(at + 5);
                 if (o.web.empty()) throw occ::InputError("--web '" + v + "': expected [ADDR:]PORT[,tls=...]");
               });
    cli.group(occ::CliGroup::cluster);
    cli.option("lookahead", &o.lookahead, 1, 64,
               "cameras sent ahead of the displayed frame (lockstep: the latency in frames; latest: the most frames "
               "in flight); 3 pays over links with a few ms of delay");
    if (!cli.parse(argc, argv)) return 0;
    if (!o.out.empty()) {
      std::error_code ec;
      std::filesystem::create_directories(o.out, ec);
      if (ec) throw occ::InputError("--out '" + o.out + "': cannot create the folder: " + ec.message());
      o.record = (std::filesystem::path(o.out) / "path.csv").string();
    }
    if (o.window && !o.web.empty()) throw occ::InputError("--web: not with --window (one display)");
    if (!o.web.empty()) occ::parse_web_options(o.web, o.web_tls);  // a bad --web fails before the scene loads
    if (o.path.empty()) o.path = o.viewer() ? "interactive" : "walk:60";
    if (o.path == "interactive" && !o.viewer()) throw occ::InputError("--path interactive needs --window or --web");
    if (o.path != "interactive") {  // a bad --path fails now, not after the scene has loaded
      occ::Aabb unit;
      unit.grow(glm::dvec3(0.0));
      unit.grow(glm::dvec3(1.0));
      occ::load_camera_path(o.path, unit, {o.width, o.height});
    }
    if (o.connect.empty()) {
      if (!key_file.empty()) throw occ::InputError("--cluster-key-file is for a cluster (--connect)");
      return occ::run_reference(o);
    }
    if (o.connect.size() > 2)
      throw occ::InputError("give --connect twice (both switch nodes) or once (an occlusion_server), not " +
                            std::to_string(o.connect.size()) + " times");
    if (o.exact) throw occ::InputError("--exact is the reference renderer's (no --connect)");
    for (const auto& c : o.connect) occ::net::parse_endpoint("connect", c);  // fail before loading the scene
    o.key = occ::load_cluster_key(key_file);
    return occ::run_cluster_client(o);
  });
}
