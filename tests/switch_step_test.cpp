// What the three processes share (protocol/cluster): the diff sender, the typed configuration and
// its flags, the endpoint parser. No GL, no sockets. (The switch step's traversal and fronts are
// checked frame by frame in lod_front_test.cpp.)
#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include "common/cli.hpp"
#include "common/error.hpp"
#include "common/hash.hpp"
#include "protocol/cluster/cluster.hpp"
#include "protocol/net/endpoint.hpp"
#include "protocol/visible_set.hpp"

using namespace occ;

namespace {

VisibleSet set_of(uint32_t limit, const std::vector<uint32_t>& ids) {
  VisibleSet s(limit);
  for (uint32_t id : ids) s.insert(id);
  return s;
}

std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST(DiffSender, StreamsNewIdsInChunksThenRemovedThenAnEndOfFrameThatVerifies) {
  const VisibleSet prev = set_of(100, {1, 2, 3, 4, 5});
  std::vector<wire::Message> sent;
  DiffSender out(2, [&](const wire::Message& m) { sent.push_back(m); });
  out.begin(7, prev);
  for (uint32_t id : {3u, 10u, 11u, 12u, 5u, 13u}) out.visible(id);  // 3 and 5 were visible before
  const VisibleSet cur = set_of(100, {3, 5, 10, 11, 12, 13});
  ASSERT_EQ(sent.size(), 2u);  // two full chunks of added ids went out as soon as they filled
  const wire::EndOfFrame eof = out.end(cur);
  // Added: {10,11}, {12,13}; removed 1, 2, 4 in chunks of 2.
  ASSERT_EQ(sent.size(), 4u);
  EXPECT_EQ(std::get<wire::NodeDiff>(sent[0]).added, (std::vector<uint32_t>{10, 11}));
  EXPECT_EQ(std::get<wire::NodeDiff>(sent[1]).added, (std::vector<uint32_t>{12, 13}));
  std::vector<uint32_t> removed;
  for (size_t i = 2; i < sent.size(); ++i) {
    const auto& d = std::get<wire::NodeDiff>(sent[i]);
    EXPECT_EQ(d.frame, 7u);
    EXPECT_TRUE(d.added.empty());
    removed.insert(removed.end(), d.removed.begin(), d.removed.end());
  }
  std::sort(removed.begin(), removed.end());
  EXPECT_EQ(removed, (std::vector<uint32_t>{1, 2, 4}));
  EXPECT_EQ(eof.frame, 7u);
  EXPECT_EQ(eof.total_added, 4u);
  EXPECT_EQ(eof.total_removed, 3u);
  // A receiver holding prev rebuilds cur and accepts the end of frame.
  VisibleSet rebuilt = prev;
  DiffReceiver in;
  for (const auto& m : sent) ASSERT_FALSE(in.on_diff(rebuilt, std::get<wire::NodeDiff>(m)));
  EXPECT_FALSE(in.on_end_of_frame(rebuilt, eof));
  EXPECT_TRUE(rebuilt == cur);
}

// What a frame would take with the whole set sent (the run table and stats.csv's full_set_bytes):
// the encoded NodeDiff chunks of every id.
TEST(DiffSender, FullSetBytesAreTheEncodedChunksOfTheWholeSet) {
  for (uint32_t n : {0u, 1u, 99u, 100u, 101u, 2500u}) {
    for (uint32_t chunk : {1u, 17u, 100u}) {
      std::vector<uint32_t> ids(n);
      for (uint32_t i = 0; i < n; ++i) ids[i] = 3 * i;
      uint64_t bytes = 0;
      for (const wire::NodeDiff& d : wire::chunk_node_diff(7, ids, {}, chunk)) bytes += wire::encode(d).size();
      EXPECT_EQ(wire::full_set_wire_bytes(n, chunk), bytes) << n << " ids in chunks of " << chunk;
    }
  }
}

TEST(DiffSender, RandomFramesRebuildOnTheReceiver) {
  std::mt19937 rng(3);
  VisibleSet sender_set(500), receiver_set(500);
  DiffReceiver in;
  std::vector<wire::Message> sent;
  DiffSender out(17, [&](const wire::Message& m) { sent.push_back(m); });
  for (uint32_t f = 0; f < 40; ++f) {
    std::vector<uint32_t> found;
    for (uint32_t id = 0; id < 500; ++id)
      if (rng() % 7 == 0) found.push_back(id);
    sent.clear();
    out.begin(f, sender_set);
    for (uint32_t id : found) out.visible(id);
    const VisibleSet cur = set_of(500, found);
    const wire::EndOfFrame eof = out.end(cur);
    for (const auto& m : sent) {
      EXPECT_LE(std::get<wire::NodeDiff>(m).added.size() + std::get<wire::NodeDiff>(m).removed.size(), 17u);
      ASSERT_FALSE(in.on_diff(receiver_set, std::get<wire::NodeDiff>(m)));
    }
    ASSERT_FALSE(in.on_end_of_frame(receiver_set, eof)) << "frame " << f;
    sender_set = cur;
  }
  EXPECT_TRUE(receiver_set == sender_set);
}

TEST(DiffSender, RefusesChunksOutsideTheWireLimits) {
  EXPECT_THROW(DiffSender(0, [](const wire::Message&) {}), std::invalid_argument);
  EXPECT_THROW(DiffSender(wire::kMaxDiffIds + 1, [](const wire::Message&) {}), std::invalid_argument);
}

TEST(ClusterConfig, FlagsAreTypedAndTheHashIsTheFlagWords) {
  ClusterConfig c;
  Cli cli("prog", "", "");
  add_cluster_options(cli, c);
  std::vector<std::string> a{"prog", "--camera-mode", "latest", "--front-tracking", "off", "--visible-pixel-lod",
                             "on", "--pixel-error", "2"};
  std::vector<char*> argv;
  for (auto& s : a) argv.push_back(s.data());
  ASSERT_TRUE(cli.parse(int(argv.size()), argv.data()));
  EXPECT_EQ(c.camera_mode, CameraMode::latest);
  EXPECT_FALSE(c.front_tracking);
  EXPECT_TRUE(c.visible_pixel_lod);
  EXPECT_EQ(c.lod_policy(600).viewport_height_px, 600.0);
  EXPECT_EQ(c.lod_policy(600).tau, 2.0);
  // The hash is over the words the flags are spelled with (so it names the same settings on every
  // build), and any changed setting changes it.
  Hasher h;
  h.str("latest");
  h.f64(2.0);
  h.str("on");
  h.str("off");
  EXPECT_EQ(c.hash(), h.value());
  ClusterConfig d = c;
  d.front_tracking = true;
  EXPECT_NE(d.hash(), c.hash());
  EXPECT_EQ(error_of([&] {
              std::vector<std::string> b{"prog", "--front-tracking", "yes"};
              std::vector<char*> v;
              for (auto& s : b) v.push_back(s.data());
              cli.parse(int(v.size()), v.data());
            }),
            "--front-tracking 'yes': expected one of on|off");
  EXPECT_NE(cli.help().find("--camera-mode lockstep|latest"), std::string::npos) << cli.help();
}

TEST(CameraPacket, ReceiversCheckTheViewport) {
  Camera cam = Camera::look_at({0, 0, 5}, {0, 0, 0}, {0, 1, 0}, 60, 1.0, 0.1, 100);
  const wire::Camera w = to_wire(4, cam, {640, 480});
  EXPECT_FALSE(viewport_mismatch(w, {640, 480}));
  ASSERT_TRUE(viewport_mismatch(w, {480, 640}));
  EXPECT_EQ(*viewport_mismatch(w, {480, 640}), "camera 4 is for a 640x480 viewport, this process renders 480x640");
  const Camera back = from_wire(w);
  EXPECT_EQ(back.eye, cam.eye);
  EXPECT_EQ(back.fovy_rad, cam.fovy_rad);
}

TEST(Endpoint, OneParserForListenPeerConnectAndTheRelay) {
  net::Endpoint e = net::parse_endpoint("peer", "10.0.0.2:7000");
  EXPECT_EQ(e.host, "10.0.0.2");
  EXPECT_EQ(e.port, 7000);
  e = net::parse_endpoint("connect", "7001");  // port alone: loopback
  EXPECT_EQ(e.host, "127.0.0.1");
  EXPECT_EQ(e.port, 7001);
  EXPECT_EQ(error_of([] { net::parse_endpoint("peer", "x:99999"); }),
            "--peer 'x:99999': expected HOST:PORT with PORT 0..65535");
  EXPECT_EQ(error_of([] { net::parse_endpoint("listen", ":1"); }), "--listen ':1': empty host");
  // The relay's rules: a host is required and its target port cannot be 0.
  EXPECT_EQ(error_of([] { net::parse_endpoint("target", "7000", {true, 1}); }),
            "--target '7000': expected HOST:PORT with PORT 1..65535");
  EXPECT_EQ(error_of([] { net::parse_endpoint("target", "h:0", {true, 1}); }),
            "--target 'h:0': expected HOST:PORT with PORT 1..65535");
  EXPECT_EQ(net::parse_endpoint("target", "h:9", {true, 1}).host, "h");
}
