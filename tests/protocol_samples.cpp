// One valid instance of every message type (several for the variable-size ones), shared by the
// protocol tests. Declared where used as: std::vector<occ::wire::Message> sample_messages();
#include <vector>

#include "protocol/wire.hpp"

using namespace occ::wire;

std::vector<Message> sample_messages() {
  Hello hello;
  hello.role = Role::switch_node;
  hello.node_id = 1;
  hello.viewport_width_px = 1920;
  hello.viewport_height_px = 1080;
  hello.scene_fingerprint = 0x0123456789abcdefULL;
  hello.arity = 8;
  hello.leaf_items = 1;
  hello.cluster_triangles = 2048;
  hello.config_hash = 0xfedcba9876543210ULL;
  hello.name = "switch-1 \xc3\xa9\xe2\x9c\x93";  // "switch-1 é✓"
  hello.occlusion_backend = "cpu-pyramid";
  Hello keyed = hello;
  keyed.role = Role::render_client;
  keyed.auth = Auth::cluster_key;
  for (size_t i = 0; i < keyed.nonce.size(); ++i) keyed.nonce[i] = uint8_t(0xa0 + i);
  Proof proof;
  for (size_t i = 0; i < proof.mac.size(); ++i) proof.mac[i] = uint8_t(255 - 7 * i);

  Camera cam;
  cam.frame = 0x01020304;
  cam.eye[0] = 1.5e7;
  cam.eye[1] = -2.25;
  cam.eye[2] = 1e-300;
  cam.orientation[0] = 0.5;
  cam.orientation[1] = 0.5;
  cam.orientation[2] = -0.5;
  cam.orientation[3] = 0.5;
  cam.fovy_rad = 0.9;
  cam.aspect = 16.0 / 9.0;
  cam.near_dist = 0.01;
  cam.far_dist = 1e5;
  cam.viewport_width_px = 1920;
  cam.viewport_height_px = 1080;
  cam.section_count = 2;  // a cut: x >= 3 and -y >= -1e6
  const double planes[2][4] = {{1, 0, 0, -3}, {0, -1, 0, 1e6}};
  for (int i = 0; i < 2; ++i)
    for (int k = 0; k < 4; ++k) cam.sections[i][k] = planes[i][k];

  NodeDiff diff{7, {1, 2, 3, 0xffffffffu, 100000}, {4, 5}};
  NodeDiff only_removed{8, {}, {9, 10, 11}};
  NodeDiff empty{9, {}, {}};

  EndOfFrame eof{12, 300, 200, 4000, 0x1111222233334444ULL, 0x5555666677778888ULL,
                 1234, 5678, 910, 123456789012ULL, 0xa1a2a3a4u, 0xb1b2b3b4u, 0xc1c2c3c4u, 0xd1d2d3d4u};

  return {Message{hello},      Message{Hello{}}, Message{cam},           Message{Camera{}},
          Message{diff},       Message{only_removed}, Message{empty},   Message{eof},
          Message{Bye{"done"}}, Message{Bye{""}}, Message{keyed},   Message{proof},
          Message{Proof{}},     Message{Resync{41, 3, 1}}, Message{Resync{}}};
}
