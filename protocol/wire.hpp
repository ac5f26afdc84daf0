// occswitch wire format: the single source of truth for every byte the three processes exchange.
// Bytes only (no sockets); depends on the standard library (wire.cpp: and common/hash.hpp's hex).
//
// Encoding rules
//   - All integers are little-endian and fixed width; f64 is the IEEE-754 binary64 bit pattern
//     stored as a little-endian u64. Strings are a u16 byte count followed by UTF-8 bytes (no
//     terminator, no control characters). Nothing is ever memcpy'd from a struct.
//   - A stream is a sequence of frames: a 6-byte header, then the payload.
//
// Frame header (6 bytes)
//   off size field
//     0  u16  type            1 hello, 2 camera, 3 node_diff, 4 end_of_frame, 5 bye, 6 proof,
//                             7 resync
//     2  u32  payload_bytes   <= kMaxPayloadBytes and within the type's size bounds below
//
// Hello (81 + name_bytes + backend_bytes; 81..177) — first message on every connection, in both directions
//     0  u32  magic           kMagic 0x5753434F (bytes "OCSW")
//     4  u16  version         kProtocolVersion
//     6  u8   role            0 switch_node, 1 render_client, 2 tool
//     7  u8   node_id         switch node id (0/1); free for the other roles
//     8  u32  viewport_width_px    0..16384 (0 = none, e.g. a tool)
//    12  u32  viewport_height_px   0..16384
//    16  u64  scene_fingerprint    Hierarchy::fingerprint()
//    24  u32  arity                build parameters that must agree ...
//    28  u32  leaf_items
//    32  u32  cluster_triangles
//    36  u64  config_hash          ... and a hash of every other setting that must agree
//    44  u8   auth                 0 none, 1 cluster key (HMAC-SHA256 challenge-response, below)
//    45  u8[32] nonce              auth 1: fresh random bytes for this connection; auth 0: all zero
//    77  u16  name_bytes           <= kMaxNameBytes
//    79  u8[] name                 for logs
//     .  u16  backend_bytes        <= kMaxBackendBytes
//     .  u8[] occlusion_backend    a switch node's occlusion back end, as its start-up line names it
//                                  (the render client's run table); empty for the other roles.
//                                  Lower-case ASCII letters, digits and '-' only
//
// Camera (102 + 32 * section_count) — camera -> world rotation, camera looks down -Z, +Y up
//     0  u32  frame
//     4  f64  eye x, y, z
//    28  f64  orientation w, x, y, z   unit quaternion (|q| within 1e-6 of 1)
//    60  f64  fovy_rad                 in (0, pi)
//    68  f64  aspect                   > 0
//    76  f64  near                     > 0
//    84  f64  far                      > near
//    92  u32  viewport_width_px        1..16384
//    96  u32  viewport_height_px       1..16384
//   100  u8   occlusion                1: the switch culls this camera's frame with occlusion (OR,
//                                      HC's queries); 0: its HC node sends the frustum set (no OR,
//                                      no queries). The render client's OcclusionGate chooses
//                                      (common/cull/occlusion_gate.hpp)
//   101  u8   section_count            0..6 section planes (common/section.hpp)
//   102  f64  sections [section_count][4]  A, B, C, D of each: keeps A*x + B*y + C*z + D >= 0
//                                      (world coordinates; (A, B, C) a unit normal within 1e-6)
//
// NodeDiff (12 + 4 * (added_count + removed_count)) — one chunk of δ(f,f-1) and δ(f-1,f)
//     0  u32  frame
//     4  u32  added_count
//     8  u32  removed_count
//    12  u32  added ids [added_count]
//     .  u32  removed ids [removed_count]     no id twice in one message (in either list)
//
// EndOfFrame (68) — closes frame `frame` of a diff stream
//     0  u32  frame
//     4  u32  total_added       ids added in all of this frame's NodeDiff chunks
//     8  u32  total_removed     ids removed in all of this frame's NodeDiff chunks
//    12  u32  visible_count     |V_f|
//    16  u64  set_hash          set_hash(V_f), see visible_set.hpp
//    24  u64  front_hash        front_hash(V') of front tracking (common/cull/front.hpp); 0 when unused
//    32  u32  queries           sender's per-frame statistics: occlusion queries issued,
//    36  u32  hc_us               HC time (microseconds, wall clock),
//    40  u32  or_us               time spent on the OR for this frame (microseconds, wall clock,
//                                 waits for the other node's stream excluded),
//    44  u64  triangles           triangles drawn at the chosen LOD (0 = unknown),
//    52  u32  hc_cpu_us           CPU time of the sender's whole process during HC (all threads:
//                                 llvmpipe's included; microseconds),
//    56  u32  or_cpu_us           CPU time of the sender's process during this frame's OR,
//    60  u32  or_tail_cpu_us      ... of which after the last diff chunk with additions of the
//                                 other node's stream for the previous frame arrived (or its
//                                 EndOfFrame, if none): the OR work on the critical path from one
//                                 HC to the next (0 = not measured),
//    64  u32  or_tail_us          the same stretch in wall-clock time (microseconds)
//
// Bye (2 + reason_bytes; 2..1026) — the sender closes after it. Reason kByeDone ("done") means it
// finished cleanly; any other reason says why it failed or gave up.
//     0  u16  reason_bytes      <= kMaxReasonBytes
//     2  u8[] reason
//
// Proof (32) — the cluster key proven (docs/security.md); only in the handshake, only with auth 1
//     0  u8[32] mac             HMAC-SHA256(key, proof_input(direction, prover hello, verifier hello))
//
// Resync (12) — render client -> switch node, and back (the node's acknowledgement). The cluster
// starts over at frame `frame` with empty visible sets (V_{frame-1} = V_{frame-2} = empty, fronts
// from the root), as at frame 0: with nodes = 2 as the switch (node frame % 2 does HC(frame)), with
// nodes = 1 the receiving node alone does OR and HC of every frame (its peer is dropped). `epoch`
// numbers the render client's resyncs (1, 2, ...). The node sends the same Resync back before its
// first message of frame `frame`: whatever the render client received from it before is stale.
// With nodes = 2 each node also sends it to the other node, as a marker on their link: what the
// other node receives before it belongs to the old run of frames and is skipped.
//     0  u32  frame
//     4  u32  epoch             >= 1
//     8  u32  nodes             1 or 2
//
// Handshake (protocol/net/transport.hpp handshake()). C = the side that connected, A = the side
// that accepted. C sends its Hello first; A answers with its Hello once it has C's (so a refusal,
// e.g. "busy", can take the place of A's last message). With auth 0 on both sides that is all.
// With auth 1 on both: C sends Proof(connector), A verifies it and answers Proof(acceptor) (or
// Bye(reason) when it refuses C), C verifies that. A key on one side only is refused on both
// sides. proof_input() (below) is the MAC'd message: a direction label, the prover's and the
// verifier's role and node id, the verifier's nonce (the challenge) and the prover's own nonce:
//     "occswitch proof v1 connector" (28 bytes) or "occswitch proof v1 acceptor" (27), ASCII
//     u8 prover role, u8 prover node_id, u8 verifier role, u8 verifier node_id,
//     u8[32] verifier nonce, u8[32] prover nonce
// A's proof is sent only after C's verified, so A never MACs for a process without the key.
#pragma once
#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "protocol/result.hpp"

namespace occ::wire {

constexpr uint32_t kMagic = 0x5753434F;  // "OCSW" in little-endian byte order
constexpr uint16_t kProtocolVersion = 9;  // 2: EndOfFrame carries CPU times; 3: cluster key (auth, proof); 4: Resync;
                                          // 5: Camera.occlusion; 6: Camera.occlusion 2 (selected occluders);
                                          // 7: Camera.occlusion 0 or 1 again (selected occluders retired);
                                          // 8: Hello.occlusion_backend; 9: Camera.sections
constexpr size_t kHeaderBytes = 6;
constexpr uint32_t kMaxPayloadBytes = 1u << 20;
constexpr size_t kMaxNameBytes = 64;
constexpr size_t kMaxBackendBytes = 32;
constexpr size_t kMaxReasonBytes = 1024;
constexpr uint32_t kMaxViewportPx = 16384;
constexpr uint32_t kDefaultDiffChunkIds = 100;  // the paper's buffer size b
constexpr uint32_t kMaxDiffIds = (kMaxPayloadBytes - 12) / 4;  // ids in one NodeDiff
constexpr size_t kNonceBytes = 32;
constexpr size_t kProofBytes = 32;  // HMAC-SHA256

enum class Type : uint16_t {
  hello = 1, camera = 2, node_diff = 3, end_of_frame = 4, bye = 5, proof = 6, resync = 7
};
constexpr size_t kTypeCount = 7;
constexpr size_t type_index(Type t) { return static_cast<size_t>(t) - 1; }  // 0..kTypeCount-1
std::string_view type_name(Type t);  // "hello", ...; "unknown" for values outside the enum

enum class Role : uint8_t { switch_node = 0, render_client = 1, tool = 2 };
std::string_view role_name(Role r);  // "switch_node", ...; "unknown" outside the enum

enum class Auth : uint8_t { none = 0, cluster_key = 1 };
using Nonce = std::array<uint8_t, kNonceBytes>;

struct Hello {
  Role role = Role::tool;
  uint8_t node_id = 0;
  uint32_t viewport_width_px = 0;
  uint32_t viewport_height_px = 0;
  uint64_t scene_fingerprint = 0;
  uint32_t arity = 0;
  uint32_t leaf_items = 0;
  uint32_t cluster_triangles = 0;
  uint64_t config_hash = 0;
  Auth auth = Auth::none;
  Nonce nonce{};  // auth none: all zero
  std::string name;
  std::string occlusion_backend;  // switch_node: e.g. "cpu", "queries"; "" for the other roles
  bool operator==(const Hello&) const = default;
};

struct Camera {
  uint32_t frame = 0;
  double eye[3] = {0, 0, 0};
  double orientation[4] = {1, 0, 0, 0};  // w, x, y, z
  double fovy_rad = 1.0471975511965976;   // 60 degrees
  double aspect = 1.0;
  double near_dist = 0.1;
  double far_dist = 1000.0;
  uint32_t viewport_width_px = 1;
  uint32_t viewport_height_px = 1;
  uint8_t occlusion = 1;  // 0 or 1
  uint8_t section_count = 0;
  double sections[6][4] = {};  // the first section_count are sent
  bool operator==(const Camera& o) const;
};

struct NodeDiff {
  uint32_t frame = 0;
  std::vector<uint32_t> added;
  std::vector<uint32_t> removed;
  bool operator==(const NodeDiff&) const = default;
};

struct EndOfFrame {
  uint32_t frame = 0;
  uint32_t total_added = 0;
  uint32_t total_removed = 0;
  uint32_t visible_count = 0;
  uint64_t set_hash = 0;
  uint64_t front_hash = 0;
  uint32_t queries = 0;
  uint32_t hc_us = 0;
  uint32_t or_us = 0;
  uint64_t triangles = 0;
  uint32_t hc_cpu_us = 0;
  uint32_t or_cpu_us = 0;
  uint32_t or_tail_cpu_us = 0;
  uint32_t or_tail_us = 0;
  bool operator==(const EndOfFrame&) const = default;
};

inline constexpr const char* kByeDone = "done";

struct Bye {
  std::string reason;
  bool operator==(const Bye&) const = default;
};

struct Proof {
  std::array<uint8_t, kProofBytes> mac{};
  bool operator==(const Proof&) const = default;
};

// A refusal of a connector that is otherwise welcome, because the acceptor already serves its
// slot: the Bye reason starts with this (switch node 1 retries on it; a render client gives up).
inline constexpr const char* kByeBusy = "busy: ";

struct Resync {
  uint32_t frame = 0;
  uint32_t epoch = 1;
  uint32_t nodes = 2;
  bool operator==(const Resync&) const = default;
};

using Message = std::variant<Hello, Camera, NodeDiff, EndOfFrame, Bye, Proof, Resync>;
Type type_of(const Message& m);

// The rules a decoded message must satisfy beyond its layout (finite camera values, unit
// quaternion, near/far, viewport, duplicate ids, string lengths and text, back-end names, id count). nullopt when
// valid, else the reason, prefixed by the message type ("camera: near 0 <= 0"). decode() applies
// exactly these rules; senders call it to fail locally instead of being rejected by the peer.
std::optional<std::string> invalid_reason(const Message& m);

// Header + payload. Total function: writes whatever the struct holds (check invalid_reason()
// first); the payload of a valid message is at most kMaxPayloadBytes.
std::vector<uint8_t> encode(const Message& m);

struct FrameHeader {
  Type type;
  uint32_t payload_bytes;
};

// Streaming step 1: validates the first kHeaderBytes of `bytes` (known type, payload length
// within kMaxPayloadBytes and the type's bounds) so a reader can size its buffer safely.
// Bytes beyond the header are ignored.
Result<FrameHeader> decode_header(std::span<const uint8_t> bytes);

// Streaming step 2: decodes one payload of the given type (the header's bounds are re-checked).
// Rejects truncation, trailing bytes, bad magic/version, inconsistent counts, and every
// invalid_reason(). Never allocates more than the payload size.
Result<Message> decode_payload(Type type, std::span<const uint8_t> payload);

// Decodes exactly one whole frame (header + payload, no more, no less).
Result<Message> decode(std::span<const uint8_t> frame);

// The bytes a Proof's MAC covers (layout in the header comment): who proves (the side that
// connected or the one that accepted), the prover's Hello and the verifier's Hello (their role,
// node id and nonce are used).
enum class ProofDirection : uint8_t { connector = 0, acceptor = 1 };
std::vector<uint8_t> proof_input(ProofDirection d, const Hello& prover, const Hello& verifier);

// Splits one frame's diff into NodeDiff messages of at most max_ids ids each (added first, then
// removed; input order kept). No ids -> no messages. Throws std::invalid_argument unless
// 1 <= max_ids <= kMaxDiffIds.
std::vector<NodeDiff> chunk_node_diff(uint32_t frame, std::span<const uint32_t> added,
                                      std::span<const uint32_t> removed,
                                      uint32_t max_ids = kDefaultDiffChunkIds);

// The bytes on the wire (headers included) of one frame's whole visible set of `ids` sent as
// NodeDiff chunks of at most `max_ids` added ids: what a frame would take without diffs.
inline uint64_t full_set_wire_bytes(uint64_t ids, uint32_t max_ids = kDefaultDiffChunkIds) {
  const uint64_t messages = (ids + max_ids - 1) / max_ids;
  return messages * (kHeaderBytes + 12) + 4 * ids;
}

}  // namespace occ::wire
