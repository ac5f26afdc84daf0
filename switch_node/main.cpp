// switch_node: one half of the occlusion switch. Run two (--id 0 and --id 1) and a render_client.
#include <cstdlib>
#include <string>

#include "common/cli.hpp"
#include "common/error.hpp"
#include "common/gl/startup.hpp"
#include "common/memory.hpp"
#include "switch_node/node.hpp"

int main(int argc, char** argv) {
  // No llvmpipe rasteriser threads unless asked for (LP_NUM_THREADS): a node's work is many small
  // passes it waits for, and Mesa 22.3's rasteriser threads can corrupt the heap (a fence freed
  // while its mutex is still being unlocked; docs/hard_cases.md).
  ::setenv("LP_NUM_THREADS", "0", 0);
  occ::use_huge_pages(argv);
  return occ::run_main([&] {
    occ::NodeOptions o;
    occ::Cli cli("switch_node", "--id 0|1 [--peer HOST:PORT] [options]",
                 "One node of the occlusion switch: alternately renders the occluders (OR, depth only)\n"
                 "and culls with hardware occlusion queries (HC), streaming visible-set diffs to the\n"
                 "render client and to the other node. Node 0 listens for node 1 and the render client;\n"
                 "node 1 connects to node 0 (--peer) and listens for the render client.");
    cli.group(occ::CliGroup::cluster);
    cli.option("id", &o.id, 0, 1, "which node of the switch (HC on frames f with f % 2 == id)");
    occ::add_view_options(cli, o.scene, &o.width, &o.height, &o.gl, "must match the render client");
    occ::add_listen_options(cli, o.listen);
    cli.option("peer", &o.peer, "HOST:PORT", "node 1 only: switch node 0's address");
    cli.option("timeout-ms", &o.timeout_ms, 100, 3600000, "longest wait for a peer or a message (for the next camera: twice this)");
    std::string key_file;
    occ::add_key_option(cli, &key_file);
    cli.custom("serve", "N|forever", "",
               "stay up for N successive render clients (forever: no end), one at a time (both nodes need it); a "
               "second client while one is served is told the cluster is busy (default: one client, then exit)",
               [&o](const std::string& v) {
                 o.serve = true;
                 o.sessions = v == "forever" ? 0 : int(occ::Cli::whole("serve", v, 1, 1000000, " or forever"));
               });
    occ::add_cluster_options(cli, o.config);
    occ::add_hc_options(cli, o.hc);
    if (!cli.parse(argc, argv)) return 0;
    if (o.id == 1 && o.peer.empty()) throw occ::InputError("--peer is required for --id 1 (switch node 0's HOST:PORT)");
    if (o.id == 0 && !o.peer.empty()) throw occ::InputError("--peer is for --id 1 only: node 0 listens for node 1");
    occ::resolve_listen(o.listen);  // fail before loading the scene
    if (!o.peer.empty()) occ::net::parse_endpoint("peer", o.peer);
    o.key = occ::load_cluster_key(key_file);
    return occ::run_switch_node(o);
  });
}
