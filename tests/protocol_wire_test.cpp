// Wire format: round trips, documented layout, and every class of malformed input.
#include <cmath>
#include <limits>
#include <stdexcept>

#include <gtest/gtest.h>

#include "protocol/wire.hpp"

using namespace occ::wire;

std::vector<Message> sample_messages();

namespace {

std::string decode_error(const std::vector<uint8_t>& frame) {
  auto r = decode(frame);
  return r ? std::string("<accepted>") : r.error();
}

void put_u16(std::vector<uint8_t>& b, size_t at, uint16_t v) {
  b[at] = v & 0xff;
  b[at + 1] = v >> 8;
}
void put_u32(std::vector<uint8_t>& b, size_t at, uint32_t v) {
  for (int i = 0; i < 4; ++i) b[at + i] = static_cast<uint8_t>(v >> (8 * i));
}
// The little-endian unsigned field of `bytes` bytes at `at`.
uint64_t field(const std::vector<uint8_t>& b, size_t at, int bytes) {
  uint64_t v = 0;
  for (int i = bytes - 1; i >= 0; --i) v = v << 8 | b[at + size_t(i)];
  return v;
}

}  // namespace

TEST(Wire, EveryMessageTypeRoundTrips) {
  for (const Message& m : sample_messages()) {
    const auto bytes = encode(m);
    auto header = decode_header(bytes);
    ASSERT_TRUE(header) << header.error();
    EXPECT_EQ(header->type, type_of(m));
    EXPECT_EQ(header->payload_bytes, bytes.size() - kHeaderBytes);
    auto back = decode(bytes);
    ASSERT_TRUE(back) << type_name(type_of(m)) << ": " << back.error();
    EXPECT_EQ(*back, m) << type_name(type_of(m));
    EXPECT_FALSE(invalid_reason(m));
  }
}

TEST(Wire, EncodedSizesMatchTheDocumentedLayout) {
  EXPECT_EQ(encode(Hello{}).size(), 6u + 81u);
  Hello named;
  named.name = "abc";
  EXPECT_EQ(encode(named).size(), 6u + 81u + 3u);
  named.occlusion_backend = "cpu";
  EXPECT_EQ(encode(named).size(), 6u + 81u + 3u + 3u);
  EXPECT_EQ(encode(Proof{}).size(), 6u + 32u);
  EXPECT_EQ(encode(Camera{}).size(), 6u + 102u);
  Camera frustum_only;
  frustum_only.occlusion = 0;
  EXPECT_EQ(encode(frustum_only)[6 + 100], 0);  // occlusion
  EXPECT_EQ(encode(Camera{})[6 + 100], 1);
  EXPECT_EQ(encode(Camera{})[6 + 101], 0);  // no section planes
  Camera cut;
  cut.section_count = 1;
  cut.sections[0][1] = 1;  // keeps y >= 0
  EXPECT_EQ(encode(cut).size(), 6u + 102u + 32u);
  EXPECT_EQ(encode(cut)[6 + 101], 1);
  EXPECT_EQ(decode(encode(cut)).value(), Message{cut});
  cut.section_count = 7;
  std::vector<uint8_t> seven = encode(Camera{});
  seven[6 + 101] = 7;
  EXPECT_FALSE(decode(seven));
  Camera bent;
  bent.section_count = 1;
  bent.sections[0][0] = 2;  // not a unit normal
  EXPECT_FALSE(decode(encode(bent)));
  EXPECT_EQ(encode(NodeDiff{1, {1, 2, 3}, {4}}).size(), 6u + 12u + 16u);
  EXPECT_EQ(encode(EndOfFrame{}).size(), 6u + 68u);
  EXPECT_EQ(encode(Bye{"bye"}).size(), 6u + 2u + 3u);
  const auto resync = encode(Resync{0x01020304, 5, 1});
  ASSERT_EQ(resync.size(), 6u + 12u);
  EXPECT_EQ(resync[0], 7);  // type resync (6 is proof)
  EXPECT_EQ(resync[6], 4);  // frame, u32 LE
  EXPECT_EQ(resync[10], 5);  // epoch
  EXPECT_EQ(resync[14], 1);  // nodes
}

TEST(Wire, FieldsAreLittleEndianAtTheirDocumentedOffsets) {
  const auto hello = encode(Hello{});
  EXPECT_EQ(hello[0], 1);  // type hello, u16 LE
  EXPECT_EQ(hello[1], 0);
  EXPECT_EQ(std::string(hello.begin() + 6, hello.begin() + 10), "OCSW");
  EXPECT_EQ(hello[10], kProtocolVersion);
  EXPECT_EQ(hello[11], 0);
  Hello keyed;
  keyed.config_hash = 0x0102030405060708ULL;
  keyed.auth = Auth::cluster_key;
  keyed.nonce[0] = 0x5a;
  keyed.nonce[31] = 0xa5;
  keyed.name = "n";
  const auto k = encode(keyed);
  EXPECT_EQ(field(k, 6 + 36, 8), 0x0102030405060708ULL);  // config_hash
  EXPECT_EQ(k[6 + 44], 1);                                // auth
  EXPECT_EQ(k[6 + 45], 0x5a);                             // nonce
  EXPECT_EQ(k[6 + 76], 0xa5);
  EXPECT_EQ(field(k, 6 + 77, 2), 1u);  // name_bytes
  EXPECT_EQ(k[6 + 79], 'n');
  EXPECT_EQ(field(k, 6 + 80, 2), 0u);  // backend_bytes, after the name
  keyed.occlusion_backend = "queries";
  const auto b = encode(keyed);
  ASSERT_EQ(b.size(), 6u + 81u + 1u + 7u);
  EXPECT_EQ(field(b, 6 + 80, 2), 7u);
  EXPECT_EQ(std::string(b.begin() + 6 + 82, b.end()), "queries");
  Proof proof;
  proof.mac[0] = 0x11;
  proof.mac[31] = 0x22;
  const auto p = encode(proof);
  EXPECT_EQ(p[0], 6);  // type proof
  EXPECT_EQ(p[2], 32);
  EXPECT_EQ(p[6], 0x11);
  EXPECT_EQ(p[6 + 31], 0x22);

  Camera cam;
  cam.frame = 0x01020304;
  cam.eye[0] = 1.0;  // 0x3ff0000000000000
  const auto c = encode(cam);
  EXPECT_EQ(field(c, 2, 4), 102u);  // payload length
  EXPECT_EQ(field(c, 6, 4), 0x01020304u);
  EXPECT_EQ(field(c, 6 + 4, 8), 0x3ff0000000000000ULL);

  const auto d = encode(NodeDiff{5, {0xaabbccdd}, {}});
  EXPECT_EQ(field(d, 6 + 4, 4), 1u);  // added_count
  EXPECT_EQ(field(d, 6 + 12, 4), 0xaabbccddu);

  EndOfFrame eof;
  eof.triangles = 0x0102030405060708ULL;
  eof.hc_cpu_us = 0x11121314;
  eof.or_cpu_us = 0x21222324;
  eof.or_tail_cpu_us = 0x31323334;
  eof.or_tail_us = 0x41424344;
  const auto e = encode(eof);
  EXPECT_EQ(field(e, 2, 4), 68u);  // payload length
  EXPECT_EQ(field(e, 6 + 44, 8), 0x0102030405060708ULL);  // triangles
  EXPECT_EQ(field(e, 6 + 52, 4), 0x11121314u);            // hc_cpu_us
  EXPECT_EQ(field(e, 6 + 56, 4), 0x21222324u);            // or_cpu_us
  EXPECT_EQ(field(e, 6 + 60, 4), 0x31323334u);            // or_tail_cpu_us
  EXPECT_EQ(field(e, 6 + 64, 4), 0x41424344u);            // or_tail_us
}

TEST(Wire, EveryTruncationOfEveryMessageIsRejected) {
  for (const Message& m : sample_messages()) {
    const auto bytes = encode(m);
    for (size_t len = 0; len < bytes.size(); ++len) {
      std::vector<uint8_t> prefix(bytes.begin(), bytes.begin() + len);
      const std::string err = decode_error(prefix);
      EXPECT_NE(err.find("truncated"), std::string::npos)
          << type_name(type_of(m)) << " cut to " << len << " bytes: " << err;
    }
    // The payload decoder alone, fed every shorter payload, rejects too.
    const std::span<const uint8_t> payload(bytes.data() + kHeaderBytes,
                                           bytes.size() - kHeaderBytes);
    for (size_t len = 0; len < payload.size(); ++len)
      EXPECT_FALSE(decode_payload(type_of(m), payload.first(len)))
          << type_name(type_of(m)) << " payload cut to " << len;
  }
}

TEST(Wire, TrailingBytesAreRejected) {
  for (const Message& m : sample_messages()) {
    auto bytes = encode(m);
    bytes.push_back(0);
    EXPECT_NE(decode_error(bytes).find("trailing bytes"), std::string::npos);
  }
  // Inside a payload: a string length or id count that does not cover the whole payload.
  auto hello = encode(Hello{});
  hello.push_back('x');
  put_u32(hello, 2, 82);
  EXPECT_NE(decode_error(hello).find("does not match"), std::string::npos) << decode_error(hello);
  // A name longer than what is left before the back end's length.
  auto long_name = encode(Hello{});
  put_u16(long_name, 6 + 77, 1);
  EXPECT_EQ(decode_error(long_name),
            "hello: name length 1 leaves less than the 2 bytes that follow it in the 2 bytes left in the payload");
  auto diff = encode(NodeDiff{1, {1}, {}});
  diff.insert(diff.end(), {2, 0, 0, 0});
  put_u32(diff, 2, 20);
  EXPECT_NE(decode_error(diff).find("need 4 bytes, payload has 8"), std::string::npos)
      << decode_error(diff);
}

TEST(Wire, CorruptedHeaderFieldsAreRejected) {
  auto bytes = encode(Camera{});
  for (uint16_t type : {0, 8, 255, 0xffff}) {
    auto b = bytes;
    put_u16(b, 0, type);
    EXPECT_EQ(decode_error(b), "unknown message type " + std::to_string(type));
  }
  auto wrong_size = bytes;
  put_u32(wrong_size, 2, 99);
  EXPECT_EQ(decode_error(wrong_size), "camera: payload of 99 bytes, expected 102..294");
  auto huge = encode(NodeDiff{});
  put_u32(huge, 2, 0xffffffffu);
  EXPECT_EQ(decode_error(huge), "node_diff payload too large: 4294967295 bytes (maximum 1048576)");
  put_u32(huge, 2, kMaxPayloadBytes + 1);
  EXPECT_NE(decode_error(huge).find("payload too large"), std::string::npos);
  auto misaligned = encode(NodeDiff{1, {1}, {}});
  put_u32(misaligned, 2, 17);
  misaligned.push_back(0);
  EXPECT_FALSE(decode(misaligned));
  // A header alone says nothing about the payload yet: a maximal node_diff header is fine.
  auto max_header = encode(NodeDiff{});
  put_u32(max_header, 2, kMaxPayloadBytes);
  EXPECT_TRUE(decode_header(max_header));
}

TEST(Wire, BadMagicAndVersionAreRejectedNamingBothValues) {
  auto bytes = encode(Hello{});
  auto bad_magic = bytes;
  put_u32(bad_magic, 6, 0x12345678);
  EXPECT_EQ(decode_error(bad_magic), "hello: bad magic 0x12345678 (expected 0x5753434f \"OCSW\")");
  auto bad_version = bytes;
  put_u16(bad_version, 10, 1);  // the version before EndOfFrame carried CPU times
  EXPECT_EQ(decode_error(bad_version),
            "hello: unsupported protocol version 1 (this build speaks 9)");
  put_u16(bad_version, 10, 3);  // the cluster key without Resync
  EXPECT_EQ(decode_error(bad_version),
            "hello: unsupported protocol version 3 (this build speaks 9)");
  put_u16(bad_version, 10, 4);  // cameras without the occlusion byte
  EXPECT_EQ(decode_error(bad_version),
            "hello: unsupported protocol version 4 (this build speaks 9)");
  put_u16(bad_version, 10, 5);  // cameras whose occlusion byte is 0 or 1 only
  EXPECT_EQ(decode_error(bad_version),
            "hello: unsupported protocol version 5 (this build speaks 9)");
  put_u16(bad_version, 10, 6);  // cameras whose occlusion byte may be 2 (selected occluders, retired)
  EXPECT_EQ(decode_error(bad_version),
            "hello: unsupported protocol version 6 (this build speaks 9)");
  put_u16(bad_version, 10, 7);  // hellos without the occlusion back end
  EXPECT_EQ(decode_error(bad_version),
            "hello: unsupported protocol version 7 (this build speaks 9)");
}

TEST(Wire, HelloRejectsUnknownRoleOversizedViewportAndBadNames) {
  auto bytes = encode(Hello{});
  bytes[6 + 6] = 3;
  EXPECT_EQ(decode_error(bytes), "hello: unknown role 3");

  Hello h;
  h.viewport_width_px = kMaxViewportPx + 1;
  EXPECT_EQ(*invalid_reason(h), "hello: viewport 16385x0 outside [0, 16384]");
  EXPECT_EQ(decode_error(encode(h)), *invalid_reason(h));

  const std::pair<std::string, std::string> bad_names[] = {
      {"a\nb", "hello: name: control character 0x0a at byte 1"},
      {"\x7f", "hello: name: control character 0x7f at byte 0"},
      {"ok\xff", "hello: name: invalid UTF-8 at byte 2"},
      {"\xc3", "hello: name: invalid UTF-8 at byte 0"},           // cut sequence
      {"\xc0\xaf", "hello: name: invalid UTF-8 at byte 0"},       // overlong
      {"\xed\xa0\x80", "hello: name: invalid UTF-8 at byte 0"},   // surrogate
      {"\xf4\x90\x80\x80", "hello: name: invalid UTF-8 at byte 0"},  // > U+10FFFF
  };
  for (const auto& [name, reason] : bad_names) {
    h = Hello{};
    h.name = name;
    EXPECT_EQ(invalid_reason(h).value_or(""), reason);
    EXPECT_EQ(decode_error(encode(h)), reason);
  }
  h = Hello{};
  h.name = std::string(kMaxNameBytes + 1, 'n');
  EXPECT_EQ(*invalid_reason(h), "hello: name of 65 bytes exceeds 64");
  EXPECT_EQ(decode_error(encode(h)), *invalid_reason(h));
  h.name.pop_back();
  EXPECT_TRUE(decode(encode(h)));
  h.occlusion_backend = std::string(kMaxBackendBytes, 'b');
  EXPECT_TRUE(decode(encode(h)));  // the longest Hello
  EXPECT_EQ(encode(h).size(), kHeaderBytes + 177u);
  h.occlusion_backend += 'b';
  EXPECT_EQ(decode_error(encode(h)), "hello: payload of 178 bytes, expected 81..177");
}

TEST(Wire, HelloOcclusionBackendRoundTripsAndRejectsOtherCharacters) {
  Hello h;
  h.role = Role::switch_node;
  for (const char* name : {"cpu", "queries", "cpu-pyramid", "gl2", ""}) {
    h.occlusion_backend = name;
    auto back = decode(encode(h));
    ASSERT_TRUE(back) << name << ": " << back.error();
    EXPECT_EQ(std::get<Hello>(*back).occlusion_backend, name);
  }
  const std::pair<std::string, std::string> bad[] = {
      {"CPU", "hello: occlusion_backend: character 0x43 at byte 0 (lower-case letters, digits and '-' only)"},
      {"cpu pyramid", "hello: occlusion_backend: character 0x20 at byte 3 (lower-case letters, digits and '-' only)"},
      {"gl\n", "hello: occlusion_backend: character 0x0a at byte 2 (lower-case letters, digits and '-' only)"},
      {"\xc3\xa9", "hello: occlusion_backend: character 0xc3 at byte 0 (lower-case letters, digits and '-' only)"},
      {std::string(kMaxBackendBytes + 1, 'a'), "hello: occlusion_backend of 33 bytes exceeds 32"},
  };
  for (const auto& [name, reason] : bad) {
    h.occlusion_backend = name;
    EXPECT_EQ(invalid_reason(h).value_or(""), reason);
    EXPECT_EQ(decode_error(encode(h)), reason);
  }
  // The back end's length must match the bytes after it.
  h.occlusion_backend = "cpu";
  auto bytes = encode(h);
  put_u16(bytes, 6 + 79, 2);
  EXPECT_EQ(decode_error(bytes), "hello: occlusion_backend length 2 does not match the 3 bytes left in the payload");
}

TEST(Wire, HelloRejectsUnknownAuthAndANonceWithoutAuth) {
  auto bytes = encode(Hello{});
  bytes[6 + 44] = 2;
  EXPECT_EQ(decode_error(bytes), "hello: unknown auth 2");
  bytes[6 + 44] = 0;
  bytes[6 + 50] = 1;  // a nonce byte with auth 0
  EXPECT_EQ(decode_error(bytes), "hello: nonce without auth");
  bytes[6 + 44] = 1;
  EXPECT_EQ(decode_error(bytes), "<accepted>");
}

TEST(Wire, ProofIsExactly32Bytes) {
  auto bytes = encode(Proof{});
  bytes.push_back(0);
  put_u32(bytes, 2, 33);
  EXPECT_EQ(decode_error(bytes), "proof: payload of 33 bytes, expected 32");
}

// The MAC'd bytes of a proof (wire.hpp "Handshake"): label, roles and ids, verifier's nonce, then
// the prover's; each direction, role, id and nonce changes them.
TEST(Wire, ProofInputLayout) {
  Hello c, a;
  c.role = Role::render_client;
  c.auth = a.auth = Auth::cluster_key;
  a.role = Role::switch_node;
  a.node_id = 1;
  c.nonce.fill(0xcc);
  a.nonce.fill(0xaa);
  const auto in = proof_input(ProofDirection::connector, c, a);
  const std::string label = "occswitch proof v1 connector";
  ASSERT_EQ(in.size(), label.size() + 4 + 64);
  EXPECT_EQ(std::string(in.begin(), in.begin() + long(label.size())), label);
  const size_t o = label.size();
  EXPECT_EQ(in[o], 1);      // prover role render_client
  EXPECT_EQ(in[o + 1], 0);  // prover node id
  EXPECT_EQ(in[o + 2], 0);  // verifier role switch_node
  EXPECT_EQ(in[o + 3], 1);  // verifier node id
  EXPECT_EQ(in[o + 4], 0xaa);       // the verifier's nonce: the challenge
  EXPECT_EQ(in[o + 4 + 32], 0xcc);  // the prover's own
  const auto acc = proof_input(ProofDirection::acceptor, a, c);
  EXPECT_EQ(std::string(acc.begin(), acc.begin() + 27), "occswitch proof v1 acceptor");
  EXPECT_NE(acc, in);
  Hello c2 = c;
  c2.nonce[5] ^= 1;
  EXPECT_NE(proof_input(ProofDirection::connector, c2, a), in);
  c2 = c;
  c2.node_id = 1;
  EXPECT_NE(proof_input(ProofDirection::connector, c2, a), in);
}

TEST(Wire, CameraRejectsEveryInvalidValue) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  struct Case {
    void (*edit)(Camera&, double, double);
    std::string reason;
  };
  const Case cases[] = {
      {[](Camera& c, double n, double) { c.eye[1] = n; }, "camera: non-finite eye.y (nan)"},
      {[](Camera& c, double, double i) { c.eye[2] = -i; }, "camera: non-finite eye.z (-inf)"},
      {[](Camera& c, double n, double) { c.orientation[3] = n; },
       "camera: non-finite orientation.z (nan)"},
      {[](Camera& c, double, double i) { c.far_dist = i; }, "camera: non-finite far (inf)"},
      {[](Camera& c, double n, double) { c.fovy_rad = n; }, "camera: non-finite fovy (nan)"},
      {[](Camera& c, double, double) { c.orientation[0] = 0; },
       "camera: zero-length orientation quaternion (zero-length axes)"},
      {[](Camera& c, double, double) { c.orientation[0] = 0.5; },
       "camera: orientation quaternion is not unit length (norm 0.5)"},
      {[](Camera& c, double, double) { c.fovy_rad = 0; }, "camera: fovy 0 rad outside (0, pi)"},
      {[](Camera& c, double, double) { c.fovy_rad = 3.2; },
       "camera: fovy 3.2 rad outside (0, pi)"},
      {[](Camera& c, double, double) { c.aspect = 0; }, "camera: aspect 0 <= 0"},
      {[](Camera& c, double, double) { c.near_dist = 0; }, "camera: near 0 <= 0"},
      {[](Camera& c, double, double) { c.near_dist = -1; }, "camera: near -1 <= 0"},
      {[](Camera& c, double, double) { c.far_dist = c.near_dist; },
       "camera: far 0.1 <= near 0.1"},
      {[](Camera& c, double, double) { c.far_dist = 0.05; }, "camera: far 0.05 <= near 0.1"},
      {[](Camera& c, double, double) { c.viewport_width_px = 0; },
       "camera: viewport 0x1 outside [1, 16384]"},
      {[](Camera& c, double, double) { c.viewport_height_px = 16385; },
       "camera: viewport 1x16385 outside [1, 16384]"},
      {[](Camera& c, double, double) { c.occlusion = 2; }, "camera: occlusion 2 is not 0 or 1"},
  };
  for (const Case& tc : cases) {
    Camera c;
    tc.edit(c, nan, inf);
    EXPECT_EQ(invalid_reason(c).value_or("<valid>"), tc.reason);
    EXPECT_EQ(decode_error(encode(c)), tc.reason);
  }
  Camera slightly_off;
  slightly_off.orientation[0] = 1 + 5e-7;  // within the 1e-6 tolerance
  EXPECT_FALSE(invalid_reason(slightly_off));
}

TEST(Wire, NodeDiffRejectsDuplicateIdsInOneMessage) {
  EXPECT_EQ(decode_error(encode(NodeDiff{3, {7, 8, 7}, {}})),
            "node_diff: frame 3: duplicate id 7 (2x in added, 0x in removed)");
  EXPECT_EQ(decode_error(encode(NodeDiff{3, {}, {9, 9}})),
            "node_diff: frame 3: duplicate id 9 (0x in added, 2x in removed)");
  EXPECT_EQ(decode_error(encode(NodeDiff{3, {1, 5}, {5}})),
            "node_diff: frame 3: duplicate id 5 (1x in added, 1x in removed)");
}

TEST(Wire, NodeDiffCountsThatDisagreeWithThePayloadAreRejectedBeforeAllocating) {
  auto bytes = encode(NodeDiff{1, {1, 2}, {3}});
  put_u32(bytes, 6 + 4, 0xffffffffu);  // added_count: 16 GiB of ids claimed in a 24-byte payload
  EXPECT_EQ(decode_error(bytes),
            "node_diff: frame 1: counts 4294967295 added + 1 removed need 17179869184 bytes, "
            "payload has 12");
  put_u32(bytes, 6 + 8, 0xffffffffu);
  EXPECT_FALSE(decode(bytes));
}

TEST(Wire, NodeDiffLimitIsTheMaximumPayload) {
  NodeDiff big{1, {}, {}};
  for (uint32_t i = 0; i < kMaxDiffIds; ++i) big.added.push_back(i);
  const auto bytes = encode(big);
  EXPECT_LE(bytes.size() - kHeaderBytes, kMaxPayloadBytes);
  EXPECT_TRUE(decode(bytes));
  big.removed.push_back(kMaxDiffIds);
  EXPECT_EQ(invalid_reason(big).value_or(""),
            "node_diff: frame 1: 262142 ids exceed 262141 per message");
}

TEST(Wire, ByeRejectsLongOrUnprintableReasons) {
  EXPECT_EQ(invalid_reason(Bye{std::string(kMaxReasonBytes + 1, 'r')}).value_or(""),
            "bye: reason of 1025 bytes exceeds 1024");
  EXPECT_FALSE(invalid_reason(Bye{std::string(kMaxReasonBytes, 'r')}));
  EXPECT_EQ(decode_error(encode(Bye{"a\tb"})), "bye: reason: control character 0x09 at byte 1");
}

TEST(Wire, ResyncNamesOneOrTwoNodesAndAnEpochFromOne) {
  EXPECT_FALSE(invalid_reason(Resync{7, 1, 1}));
  EXPECT_FALSE(invalid_reason(Resync{7, 2, 2}));
  EXPECT_EQ(invalid_reason(Resync{7, 1, 3}).value_or(""), "resync: frame 7: nodes 3, expected 1 or 2");
  EXPECT_EQ(decode_error(encode(Resync{7, 1, 0})), "resync: frame 7: nodes 0, expected 1 or 2");
  EXPECT_EQ(decode_error(encode(Resync{7, 0, 2})), "resync: frame 7: epoch 0 (epochs start at 1)");
}

TEST(Wire, ChunkNodeDiffSplitsIntoAtMostBIdsPerMessage) {
  std::vector<uint32_t> added(250), removed(120);
  for (uint32_t i = 0; i < added.size(); ++i) added[i] = i;
  for (uint32_t i = 0; i < removed.size(); ++i) removed[i] = 1000 + i;
  for (uint32_t b : {1u, 7u, 100u, 370u, 1000u}) {
    const auto chunks = chunk_node_diff(42, added, removed, b);
    EXPECT_EQ(chunks.size(), (370 + b - 1) / b);
    std::vector<uint32_t> got_added, got_removed;
    for (const auto& c : chunks) {
      EXPECT_EQ(c.frame, 42u);
      EXPECT_GE(c.added.size() + c.removed.size(), 1u);
      EXPECT_LE(c.added.size() + c.removed.size(), b);
      EXPECT_FALSE(invalid_reason(c));
      got_added.insert(got_added.end(), c.added.begin(), c.added.end());
      got_removed.insert(got_removed.end(), c.removed.begin(), c.removed.end());
    }
    EXPECT_EQ(got_added, added);
    EXPECT_EQ(got_removed, removed);
  }
  EXPECT_TRUE(chunk_node_diff(1, {}, {}).empty());
  EXPECT_THROW(chunk_node_diff(1, added, removed, 0), std::invalid_argument);
  EXPECT_THROW(chunk_node_diff(1, added, removed, kMaxDiffIds + 1), std::invalid_argument);
}

TEST(Wire, TypeAndRoleNames) {
  EXPECT_EQ(type_name(Type::end_of_frame), "end_of_frame");
  EXPECT_EQ(type_name(static_cast<Type>(9)), "unknown");
  EXPECT_EQ(role_name(Role::render_client), "render_client");
  EXPECT_EQ(role_name(static_cast<Role>(7)), "unknown");
  EXPECT_EQ(type_index(Type::hello), 0u);
  EXPECT_EQ(type_index(Type::proof), 5u);
  EXPECT_EQ(type_name(Type::proof), "proof");
  EXPECT_EQ(type_index(Type::resync), kTypeCount - 1);
  EXPECT_EQ(type_name(Type::resync), "resync");
}
