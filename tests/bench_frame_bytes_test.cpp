// bytes_received in the render client's stats.csv is the size of the messages that
// belong to the frame (camera, diff chunks, EndOfFrame), even when the transport's io thread has
// read many frames ahead. It used to be a difference of the connection's byte counter, which
// charged a frame with whatever the io thread had read meanwhile (0 B on some frames, several
// frames' worth on others).
#include <gtest/gtest.h>

#include <algorithm>

#include "common/camera_path.hpp"
#include "common/setup/scene_setup.hpp"
#include "integration_util.hpp"
#include "protocol/net/transport.hpp"
#include "protocol/visible_set.hpp"
#include "protocol/cluster/cluster.hpp"

using namespace occtest;
using namespace std::chrono_literals;
namespace net = occ::net;
namespace wire = occ::wire;

TEST(FrameBytes, ReceivedMessagesCarryTheirSizeOnTheWire) {
  auto listener = net::Listener::open(0);
  ASSERT_TRUE(listener) << listener.error();
  auto client = net::Connection::connect("127.0.0.1", listener->port(), 5s);
  ASSERT_TRUE(client) << client.error();
  auto server = listener->accept(5s);
  ASSERT_TRUE(server) << server.error();
  std::vector<uint32_t> many(1000);
  for (uint32_t i = 0; i < many.size(); ++i) many[i] = 3 * i;
  const std::vector<wire::Message> script = {wire::Camera{},     wire::NodeDiff{0, {1, 2, 3}, {}},
                                             wire::NodeDiff{0, {}, {7}}, wire::EndOfFrame{},
                                             wire::NodeDiff{1, many, {}}};
  for (const auto& m : script) ASSERT_FALSE(client->send(m));
  for (const auto& m : script) {
    net::Received r = server->receive(5s);
    ASSERT_TRUE(r.ok()) << r.reason;
    EXPECT_EQ(r.wire_bytes, wire::encode(m).size()) << wire::type_name(wire::type_of(m));
  }
}

// A scripted switch node 0 (the render client's single-server mode) sends every frame's stream at
// once, before the client has rendered anything, so the client's io thread reads far ahead.
TEST(FrameBytes, TheRenderClientChargesEachFrameWithItsOwnMessagesWhenItsIoThreadReadsAhead) {
  const std::string spec = "city:2x2:2:2:1";
  const uint32_t frames = 12;
  occ::SceneOptions so;
  so.spec = spec;
  occ::LoadedScene ls = occ::load_and_build(so, "frame_bytes_test");
  const occ::Viewport vp{64, 48};
  const std::vector<occ::Camera> path = occ::load_camera_path("walk:" + std::to_string(frames), ls.scene.bounds(), vp);
  ASSERT_EQ(path.size(), frames);
  std::vector<uint32_t> leaves;
  for (uint32_t id = 0; id < ls.hierarchy.size(); ++id)
    if (ls.hierarchy.node(id).leaf() && ls.hierarchy.node(id).item_count > 0) leaves.push_back(id);
  ASSERT_GE(leaves.size(), 20u);

  auto listener = net::Listener::open(0);
  ASSERT_TRUE(listener) << listener.error();
  fs::path dir = fresh_dir("frame_bytes");
  Proc rvg({bin("render_client"), "--scene", spec, "--path", "walk:" + std::to_string(frames), "--width", "64",
            "--height", "48", "--connect", "127.0.0.1:" + std::to_string(listener->port()), "--images", "off", "--out",
            dir.string()},
           dir / "client.log");
  const wire::Hello mine = occ::make_hello(wire::Role::switch_node, 0, vp, ls.fingerprint, ls.hierarchy.params(),
                                           occ::ClusterConfig{}, "scripted node", "scripted");
  auto peer = listener->accept_peer(mine, {wire::Role::render_client, std::nullopt}, 120s);
  ASSERT_TRUE(peer) << peer.error() << "\n" << rvg.log();

  // Frame f's visible set: a window of leaves whose start and length change every frame, so the
  // streams differ in size; diffs in chunks of 3 ids.
  const uint32_t limit = uint32_t(ls.hierarchy.size());
  occ::VisibleSet prev(limit);
  std::vector<uint64_t> expected;
  for (uint32_t f = 0; f < frames; ++f) {
    occ::VisibleSet cur(limit);
    const size_t first = (f * 3) % 7, count = 2 + (f * 5) % 13;
    for (size_t i = first; i < std::min(leaves.size(), first + count); ++i) cur.insert(leaves[i]);
    occ::SetDiff diff;
    for (uint32_t id : cur.ids())
      if (!prev.contains(id)) diff.added.push_back(id);
    for (uint32_t id : prev.ids())
      if (!cur.contains(id)) diff.removed.push_back(id);
    std::vector<wire::Message> msgs{occ::to_wire(f, path[f], vp)};
    for (auto& chunk : wire::chunk_node_diff(f, diff.added, diff.removed, 3)) msgs.emplace_back(std::move(chunk));
    msgs.emplace_back(occ::make_end_of_frame(f, diff, cur));
    uint64_t bytes = 0;
    for (const auto& m : msgs) {
      bytes += wire::encode(m).size();
      ASSERT_FALSE(peer->connection.send(m));
    }
    expected.push_back(bytes);
    prev = std::move(cur);
  }
  ASSERT_EQ(rvg.wait(120s), 0) << rvg.log();
  peer->connection.close(wire::kByeDone);

  auto st = read_csv(dir / "stats.csv");
  ASSERT_EQ(st["bytes_received"].size(), frames) << rvg.log();
  for (uint32_t f = 0; f < frames; ++f) EXPECT_EQ(st["bytes_received"][f], double(expected[f])) << "frame " << f;
  EXPECT_NE(expected.front(), expected.back());  // the script does vary
}
