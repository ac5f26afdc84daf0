// Bad input to the real binaries: one "error:" line naming what and where, non-zero exit, no
// crash. Also --help on every binary.
#include <gtest/gtest.h>

#include "integration_util.hpp"

using namespace occtest;
using namespace std::chrono_literals;

namespace {

Outcome run(std::vector<std::string> args, const std::string& name) {
  static fs::path dir = fresh_dir("cli");
  return run_to_end(std::move(args), dir / (name + ".log"), 60s);
}

}  // namespace

TEST(Cli, EveryBinaryHasHelp) {
  for (const char* b : {"render_client", "switch_node", "frame_diff", "occlusion_server", "link_relay", "cull_overview",
                        "protocol_bench", "scene_export"}) {
    Outcome o = run({bin(b), "--help"}, std::string(b) + "_help");
    EXPECT_EQ(o.code, 0) << b;
    EXPECT_NE(o.log.find("usage:"), std::string::npos) << b << ": " << o.log;
  }
}

TEST(Cli, RenderClientBadInputGetsOneNamedError) {
  fs::path dir = fresh_dir("cli_inputs");
  const std::string ref = bin("render_client");
  expect_one_error(run({ref, "--bogus"}, "unknown"), {"unknown flag --bogus"});
  expect_one_error(run({ref, "--width", "0"}, "w0"), {"--width '0'"});
  expect_one_error(run({ref, "--height", "100000"}, "h100k"), {"--height '100000'"});
  expect_one_error(run({ref, "--scene", "/nonexistent/x.gltf"}, "noscene"), {"/nonexistent/x.gltf"});
  std::ofstream(dir / "bad.gltf") << "{ \"asset\": {\"version\": \"2.0\"}, \"meshes\": [], \"nodes\": [{\"mesh\": 3}], "
                                     "\"scenes\": [{\"nodes\": [0]}] }";
  expect_one_error(run({ref, "--scene", (dir / "bad.gltf").string()}, "badgltf"),
                   {"bad.gltf", "node 0", "mesh 3"});
  expect_one_error(run({ref, "--scene", "city:2x2:1:2:1", "--path", "/nonexistent/p.csv"}, "nopath"),
                   {"/nonexistent/p.csv"});
  std::ofstream(dir / "nan.csv") << "0,0,1,5,0,0,0,0,1,0,60\n1,0,1,nan,0,0,0,0,1,0,60\n";
  expect_one_error(run({ref, "--scene", "city:2x2:1:2:1", "--path", (dir / "nan.csv").string()}, "nan"),
                   {"nan.csv", "line 2", "eye_z"});
  expect_one_error(run({ref, "--connect", "127.0.0.1:1", "--connect", "127.0.0.1:2", "--connect", "127.0.0.1:3"}, "three"),
                   {"--connect", "3 times"});
  expect_one_error(run({ref, "--connect", "127.0.0.1:1", "--exact"}, "exact_cluster"), {"--exact"});
  expect_one_error(run({ref, "--cluster-key-file", "/nonexistent/key"}, "key_reference"), {"--cluster-key-file"});
  expect_one_error(run({ref, "--scene", "city:0x2"}, "badcity"), {"city:0x2"});
  expect_one_error(run({ref, "--occlusion", "sometimes"}, "occlusion_word"), {"--occlusion 'sometimes'"});
  expect_one_error(run({ref, "--occlusion", "alternate:0"}, "alternate0"), {"--occlusion '0'", "1..1000"});
  expect_one_error(run({ref, "--images", "jpeg"}, "images_word"), {"--images 'jpeg'"});
  expect_one_error(run({ref, "--web", "host:nope"}, "web"), {"--web 'host:nope'"});
  expect_one_error(run({ref, "--web", ",tls=self-signed"}, "webtls"), {"--web ',tls=self-signed'"});
  expect_one_error(run({ref, "--web", "0", "--window"}, "webwin"), {"--web", "--window"});
  expect_one_error(run({ref, "--scene", "city:2x2:1:2:1", "--web",
                        "0,tls=/nonexistent/c.pem:/nonexistent/k.pem"}, "webcert"), {"tls=", "/nonexistent/c.pem"});
  expect_one_error(run({ref, "--scene", "city:2x2:1:2:1", "--web", "10.255.255.1:0"}, "webbind"),
                   {"--web '10.255.255.1:0'", "cannot listen"});
}

TEST(Cli, SwitchNodeBadInputGetsOneNamedError) {
  const std::string sn = bin("switch_node");
  expect_one_error(run({sn, "--id", "1", "--scene", "city:2x2:1:2:1"}, "nopeer"), {"--peer"});
  expect_one_error(run({sn, "--id", "2"}, "id2"), {"--id '2'"});
  expect_one_error(run({sn, "--id", "0", "--listen", "127.0.0.1:99999"}, "badlisten"), {"--listen"});
  expect_one_error(run({sn, "--id", "0", "--camera-mode", "sometimes"}, "mode"), {"--camera-mode 'sometimes'"});
}

// --listen 127.0.0.1:0 --port-file F listens on a free port of 127.0.0.1 and writes it; a port out
// of range is one named error.
TEST(Cli, SwitchNodePortAndPortFile) {
  fs::path dir = fresh_dir("cli_port");
  const fs::path pf = dir / "node0.port";
  Outcome o = run({bin("switch_node"), "--id", "0", "--scene", "city:2x2:1:2:1", "--width", "64", "--height", "64",
                   "--listen", "127.0.0.1:0", "--port-file", pf.string(), "--timeout-ms", "300"},
                  "port0");
  EXPECT_EQ(o.code, 1) << o.log;  // nobody connects: a clear timeout
  std::ifstream in(pf);
  long port = 0;
  ASSERT_TRUE(in >> port) << o.log;
  EXPECT_GT(port, 0);
  EXPECT_NE(o.log.find("listening on 127.0.0.1:" + std::to_string(port)), std::string::npos) << o.log;
  EXPECT_NE(o.log.find("no valid peer"), std::string::npos) << o.log;
  expect_one_error(run({bin("switch_node"), "--listen", "127.0.0.1:70000"}, "port70000"), {"--listen"});
  expect_one_error(run({bin("occlusion_server"), "--listen", "127.0.0.1:x"}, "portx"), {"--listen"});
  expect_one_error(run({bin("switch_node"), "--serve", "0"}, "serve0"), {"--serve '0'"});
}
