#include "protocol/wire.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <charconv>
#include <cmath>
#include <concepts>
#include <stdexcept>
#include <tuple>
#include <type_traits>

#include "common/hash.hpp"

namespace occ::wire {
namespace {

// ---- number formatting for error messages (shortest round-trip form) ----

std::string num(double v) {
  char buf[32];
  auto r = std::to_chars(buf, buf + sizeof buf, v);
  return std::string(buf, r.ptr);
}
template <std::integral T>
std::string num(T v) {
  return std::to_string(v);
}

// ---- little-endian writer / reader ----

template <class T>
struct is_byte_array : std::false_type {};
template <size_t N>
struct is_byte_array<std::array<uint8_t, N>> : std::true_type {};

class Writer {
 public:
  explicit Writer(std::vector<uint8_t>& out) : out_(out) {}
  void u8(uint8_t v) { out_.push_back(v); }
  void u16(uint16_t v) { le(v, 2); }
  void u32(uint32_t v) { le(v, 4); }
  void u64(uint64_t v) { le(v, 8); }
  void f64(double v) { u64(std::bit_cast<uint64_t>(v)); }
  void str(const std::string& s) {
    u16(static_cast<uint16_t>(s.size()));
    out_.insert(out_.end(), s.begin(), s.end());
  }
  // Writes a field list (see "field lists" below), each value at the width of its type.
  template <class... T>
  void operator()(const T&... v) {
    (field(v), ...);
  }

 private:
  void le(uint64_t v, int n) {
    for (int i = 0; i < n; ++i) out_.push_back(static_cast<uint8_t>(v >> (8 * i)));
  }
  template <class T>
  void field(const T& v) {
    if constexpr (std::is_enum_v<T>)
      field(static_cast<std::underlying_type_t<T>>(v));
    else if constexpr (std::is_array_v<T> || is_byte_array<T>::value)
      for (const auto& e : v) field(e);
    else if constexpr (std::is_same_v<T, double>)
      f64(v);
    else {
      static_assert(std::is_unsigned_v<T>);
      le(v, sizeof(T));
    }
  }
  std::vector<uint8_t>& out_;
};

// Callers check remaining() before reading; reads past the end are a programming error.
class Reader {
 public:
  explicit Reader(std::span<const uint8_t> b) : b_(b) {}
  size_t remaining() const { return b_.size() - pos_; }
  uint8_t u8() { return b_[pos_++]; }
  uint16_t u16() { return static_cast<uint16_t>(le(2)); }
  uint32_t u32() { return static_cast<uint32_t>(le(4)); }
  uint64_t u64() { return le(8); }
  double f64() { return std::bit_cast<double>(u64()); }
  std::string bytes(size_t n) {
    std::string s(reinterpret_cast<const char*>(b_.data() + pos_), n);
    pos_ += n;
    return s;
  }
  void ids(std::vector<uint32_t>& out, size_t n) {
    out.resize(n);
    for (auto& id : out) id = u32();
  }
  // Reads a field list (see "field lists" below) into its members.
  template <class... T>
  void operator()(T&... v) {
    (field(v), ...);
  }

 private:
  uint64_t le(int n) {
    uint64_t v = 0;
    for (int i = 0; i < n; ++i) v |= uint64_t(b_[pos_ + i]) << (8 * i);
    pos_ += n;
    return v;
  }
  template <class T>
  void field(T& v) {
    if constexpr (std::is_enum_v<T>) {
      std::underlying_type_t<T> u;
      field(u);
      v = static_cast<T>(u);
    } else if constexpr (std::is_array_v<T> || is_byte_array<T>::value) {
      for (auto& e : v) field(e);
    } else if constexpr (std::is_same_v<T, double>) {
      v = f64();
    } else {
      static_assert(std::is_unsigned_v<T>);
      v = static_cast<T>(le(sizeof(T)));
    }
  }
  std::span<const uint8_t> b_;
  size_t pos_ = 0;
};

// ---- sizes ----

constexpr uint32_t kHelloFixedBytes = 81;  // with name_bytes and backend_bytes, no text
constexpr uint32_t kCameraBytes = 101;  // without its section count and planes
constexpr uint32_t kSectionBytes = 32;
constexpr uint32_t kNodeDiffFixedBytes = 12;
constexpr uint32_t kEndOfFrameBytes = 68;
constexpr uint32_t kByeFixedBytes = 2;
constexpr uint32_t kProofPayloadBytes = uint32_t(kProofBytes);
constexpr uint32_t kResyncBytes = 12;

// ---- field lists: the fixed-width fields of a message in wire order (the tables in wire.hpp).
// One list serves both directions: called with a Writer it encodes `m`, with a Reader it decodes
// into `m`. A field's width is its type's (enums: the underlying type, arrays: each element).

// Hello between version and name_bytes.
constexpr void hello_fields(auto& io, auto& m) {
  io(m.role, m.node_id, m.viewport_width_px, m.viewport_height_px, m.scene_fingerprint, m.arity,
     m.leaf_items, m.cluster_triangles, m.config_hash, m.auth, m.nonce);
}
constexpr void camera_fields(auto& io, auto& m) {
  io(m.frame, m.eye, m.orientation, m.fovy_rad, m.aspect, m.near_dist, m.far_dist,
     m.viewport_width_px, m.viewport_height_px, m.occlusion);
}
constexpr void end_of_frame_fields(auto& io, auto& m) {
  io(m.frame, m.total_added, m.total_removed, m.visible_count, m.set_hash, m.front_hash,
     m.queries, m.hc_us, m.or_us, m.triangles, m.hc_cpu_us, m.or_cpu_us, m.or_tail_cpu_us, m.or_tail_us);
}

// The lists add up to the sizes above.
struct ByteCount {
  uint32_t bytes = 0;
  template <class... T>
  constexpr void operator()(const T&... v) {
    ((bytes += sizeof(v)), ...);
  }
};
template <class M>
constexpr uint32_t list_bytes(void (*list)(ByteCount&, M&)) {
  ByteCount c;
  M m{};
  list(c, m);
  return c.bytes;
}
constexpr void resync_fields(auto& io, auto& m) { io(m.frame, m.epoch, m.nodes); }
static_assert(list_bytes<Resync>(resync_fields) == kResyncBytes);
#if !defined(__clang__)  // clang 14 cannot build libstdc++'s std::string (Hello::name) in a constant expression
static_assert(list_bytes<Hello>(hello_fields) == kHelloFixedBytes - 4 - 2 - 2 - 2);  // magic, version, name_bytes, backend_bytes
#endif
static_assert(list_bytes<Camera>(camera_fields) == kCameraBytes);
static_assert(list_bytes<EndOfFrame>(end_of_frame_fields) == kEndOfFrameBytes);

struct Bounds {
  uint32_t min_bytes, max_bytes;
};
Bounds payload_bounds(Type t) {
  switch (t) {
    case Type::hello: return {kHelloFixedBytes, kHelloFixedBytes + uint32_t(kMaxNameBytes + kMaxBackendBytes)};
    case Type::camera: return {kCameraBytes + 1, kCameraBytes + 1 + 6 * kSectionBytes};
    case Type::node_diff: return {kNodeDiffFixedBytes, kMaxPayloadBytes};
    case Type::end_of_frame: return {kEndOfFrameBytes, kEndOfFrameBytes};
    case Type::bye: return {kByeFixedBytes, kByeFixedBytes + uint32_t(kMaxReasonBytes)};
    case Type::proof: return {kProofPayloadBytes, kProofPayloadBytes};
    case Type::resync: return {kResyncBytes, kResyncBytes};
  }
  return {0, 0};
}
bool known_type(uint16_t t) { return t >= 1 && t <= kTypeCount; }

std::optional<std::string> check_bounds(Type t, size_t payload_bytes) {
  const Bounds b = payload_bounds(t);
  if (payload_bytes > kMaxPayloadBytes)
    return std::string(type_name(t)) + " payload too large: " + num(payload_bytes) +
           " bytes (maximum " + num(kMaxPayloadBytes) + ")";
  if (payload_bytes < b.min_bytes || payload_bytes > b.max_bytes) {
    std::string want = b.min_bytes == b.max_bytes
                           ? num(b.min_bytes)
                           : num(b.min_bytes) + ".." + num(b.max_bytes);
    return std::string(type_name(t)) + ": payload of " + num(payload_bytes) + " bytes, expected " +
           want;
  }
  return std::nullopt;
}

// ---- semantic rules ----

// Well-formed UTF-8 without control characters (strings end up in one-line logs).
std::optional<std::string> text_error(std::string_view what, const std::string& s, size_t max) {
  if (s.size() > max)
    return std::string(what) + " of " + num(s.size()) + " bytes exceeds " + num(max);
  const auto* p = reinterpret_cast<const uint8_t*>(s.data());
  const size_t n = s.size();
  for (size_t i = 0; i < n;) {
    const uint8_t c = p[i];
    if (c < 0x80) {
      if (c < 0x20 || c == 0x7f)
        return std::string(what) + ": control character " + hex(c, 2) + " at byte " + num(i);
      ++i;
      continue;
    }
    // Sequence length from the lead byte, and the allowed range of the second byte: no
    // overlong forms, no surrogates, nothing above U+10FFFF.
    size_t len = 0;
    uint8_t lo = 0x80, hi = 0xbf;
    if (c >= 0xc2 && c <= 0xdf) {
      len = 2;
    } else if (c >= 0xe0 && c <= 0xef) {
      len = 3;
      if (c == 0xe0) lo = 0xa0;
      if (c == 0xed) hi = 0x9f;
    } else if (c >= 0xf0 && c <= 0xf4) {
      len = 4;
      if (c == 0xf0) lo = 0x90;
      if (c == 0xf4) hi = 0x8f;
    }
    bool ok = len != 0 && i + len <= n && p[i + 1] >= lo && p[i + 1] <= hi;
    for (size_t k = 2; ok && k < len; ++k) ok = p[i + k] >= 0x80 && p[i + k] <= 0xbf;
    if (!ok) return std::string(what) + ": invalid UTF-8 at byte " + num(i);
    i += len;
  }
  return std::nullopt;
}

// A back-end name: short, lower-case ASCII letters, digits and '-' (it is a word in a table).
std::optional<std::string> backend_error(const std::string& s) {
  if (s.size() > kMaxBackendBytes)
    return "occlusion_backend of " + num(s.size()) + " bytes exceeds " + num(kMaxBackendBytes);
  for (size_t i = 0; i < s.size(); ++i) {
    const char c = s[i];
    if (!((c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '-'))
      return "occlusion_backend: character " + hex(uint8_t(c), 2) + " at byte " + num(i) +
             " (lower-case letters, digits and '-' only)";
  }
  return std::nullopt;
}

std::optional<std::string> viewport_error(uint32_t w, uint32_t h, uint32_t min_px) {
  if (w < min_px || h < min_px || w > kMaxViewportPx || h > kMaxViewportPx)
    return "viewport " + num(w) + "x" + num(h) + " outside [" + num(min_px) + ", " +
           num(kMaxViewportPx) + "]";
  return std::nullopt;
}

std::optional<std::string> check(const Hello& m) {
  if (static_cast<uint8_t>(m.role) > static_cast<uint8_t>(Role::tool))
    return "unknown role " + num(static_cast<uint8_t>(m.role));
  if (auto e = viewport_error(m.viewport_width_px, m.viewport_height_px, 0)) return e;
  if (static_cast<uint8_t>(m.auth) > static_cast<uint8_t>(Auth::cluster_key))
    return "unknown auth " + num(static_cast<uint8_t>(m.auth));
  if (m.auth == Auth::none && m.nonce != Nonce{}) return std::string("nonce without auth");
  if (auto e = text_error("name", m.name, kMaxNameBytes)) return e;
  return backend_error(m.occlusion_backend);
}

std::optional<std::string> check(const Camera& m) {
  const std::pair<const char*, double> fields[] = {
      {"eye.x", m.eye[0]},         {"eye.y", m.eye[1]},         {"eye.z", m.eye[2]},
      {"orientation.w", m.orientation[0]}, {"orientation.x", m.orientation[1]},
      {"orientation.y", m.orientation[2]}, {"orientation.z", m.orientation[3]},
      {"fovy", m.fovy_rad},        {"aspect", m.aspect},        {"near", m.near_dist},
      {"far", m.far_dist}};
  for (const auto& [name, v] : fields)
    if (!std::isfinite(v)) return "non-finite " + std::string(name) + " (" + num(v) + ")";
  const double* q = m.orientation;
  const double norm = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
  if (norm == 0) return std::string("zero-length orientation quaternion (zero-length axes)");
  if (!(std::abs(norm - 1.0) <= 1e-6))
    return "orientation quaternion is not unit length (norm " + num(norm) + ")";
  if (!(m.fovy_rad > 0 && m.fovy_rad < 3.141592653589793))
    return "fovy " + num(m.fovy_rad) + " rad outside (0, pi)";
  if (!(m.aspect > 0)) return "aspect " + num(m.aspect) + " <= 0";
  if (!(m.near_dist > 0)) return "near " + num(m.near_dist) + " <= 0";
  if (m.occlusion > 1) return "occlusion " + num(m.occlusion) + " is not 0 or 1";
  if (m.section_count > 6) return "section_count " + num(m.section_count) + " > 6";
  for (int i = 0; i < m.section_count; ++i) {
    const double* s = m.sections[i];
    for (int k = 0; k < 4; ++k)
      if (!std::isfinite(s[k])) return "section " + num(i) + ": non-finite coefficient (" + num(s[k]) + ")";
    const double n = std::sqrt(s[0] * s[0] + s[1] * s[1] + s[2] * s[2]);
    if (!(std::abs(n - 1.0) <= 1e-6)) return "section " + num(i) + ": normal not unit length (" + num(n) + ")";
  }
  if (!(m.far_dist > m.near_dist))
    return "far " + num(m.far_dist) + " <= near " + num(m.near_dist);
  return viewport_error(m.viewport_width_px, m.viewport_height_px, 1);
}

std::optional<std::string> check(const NodeDiff& m) {
  const size_t total = m.added.size() + m.removed.size();
  if (total > kMaxDiffIds)
    return "frame " + num(m.frame) + ": " + num(total) + " ids exceed " + num(kMaxDiffIds) +
           " per message";
  std::vector<uint32_t> all(m.added);
  all.insert(all.end(), m.removed.begin(), m.removed.end());
  std::sort(all.begin(), all.end());
  auto dup = std::adjacent_find(all.begin(), all.end());
  if (dup == all.end()) return std::nullopt;
  const uint32_t id = *dup;
  return "frame " + num(m.frame) + ": duplicate id " + num(id) + " (" +
         num(std::count(m.added.begin(), m.added.end(), id)) + "x in added, " +
         num(std::count(m.removed.begin(), m.removed.end(), id)) + "x in removed)";
}

std::optional<std::string> check(const EndOfFrame&) { return std::nullopt; }

std::optional<std::string> check(const Bye& m) {
  return text_error("reason", m.reason, kMaxReasonBytes);
}

std::optional<std::string> check(const Proof&) { return std::nullopt; }
std::optional<std::string> check(const Resync& m) {
  if (m.nodes != 1 && m.nodes != 2) return "frame " + num(m.frame) + ": nodes " + num(m.nodes) + ", expected 1 or 2";
  if (m.epoch == 0) return "frame " + num(m.frame) + ": epoch 0 (epochs start at 1)";
  return std::nullopt;
}

// ---- payload codecs ----

void put(Writer& w, const Hello& m) {
  w.u32(kMagic);
  w.u16(kProtocolVersion);
  hello_fields(w, m);
  w.str(m.name);
  w.str(m.occlusion_backend);
}

void put(Writer& w, const Camera& m) {
  camera_fields(w, m);
  w.u8(m.section_count);
  for (int i = 0; i < m.section_count && i < 6; ++i) w(m.sections[i]);
}

void put(Writer& w, const NodeDiff& m) {
  w.u32(m.frame);
  w.u32(static_cast<uint32_t>(m.added.size()));
  w.u32(static_cast<uint32_t>(m.removed.size()));
  for (uint32_t id : m.added) w.u32(id);
  for (uint32_t id : m.removed) w.u32(id);
}

void put(Writer& w, const EndOfFrame& m) { end_of_frame_fields(w, m); }

void put(Writer& w, const Bye& m) { w.str(m.reason); }

void put(Writer& w, const Proof& m) { w(m.mac); }
void put(Writer& w, const Resync& m) { resync_fields(w, m); }

// Reads a u16-prefixed string that `tail` more bytes follow (0: it ends the payload); the caller
// has checked the fixed part.
Result<std::string> get_str(Reader& r, std::string_view what, size_t tail = 0) {
  const uint16_t n = r.u16();
  if (tail == 0 && n != r.remaining())
    return Error{std::string(what) + " length " + num(n) + " does not match the " +
                 num(r.remaining()) + " bytes left in the payload"};
  if (tail > 0 && size_t(n) + tail > r.remaining())
    return Error{std::string(what) + " length " + num(n) + " leaves less than the " + num(tail) +
                 " bytes that follow it in the " + num(r.remaining()) + " bytes left in the payload"};
  return r.bytes(n);
}

Result<Message> get_hello(Reader& r) {
  const uint32_t magic = r.u32();
  if (magic != kMagic)
    return Error{"bad magic " + hex(magic, 8) + " (expected " + hex(kMagic, 8) + " \"OCSW\")"};
  const uint16_t version = r.u16();
  if (version != kProtocolVersion)
    return Error{"unsupported protocol version " + num(version) + " (this build speaks " +
                 num(kProtocolVersion) + ")"};
  Hello m;
  hello_fields(r, m);
  auto name = get_str(r, "name", 2);  // backend_bytes follows
  if (!name) return Error{name.error()};
  m.name = std::move(*name);
  auto backend = get_str(r, "occlusion_backend");
  if (!backend) return Error{backend.error()};
  m.occlusion_backend = std::move(*backend);
  return Message{std::move(m)};
}

// Camera, EndOfFrame: a message that is its field list and nothing else.
template <class M>
Result<Message> get_fields(Reader& r, void (*fields)(Reader&, M&)) {
  M m;
  fields(r, m);
  return Message{m};
}

Result<Message> get_camera(Reader& r) {
  Camera m;
  camera_fields(r, m);
  m.section_count = r.u8();
  if (m.section_count > 6) return Error{"section_count " + num(m.section_count) + " > 6"};
  if (r.remaining() != size_t(m.section_count) * kSectionBytes)
    return Error{"section_count " + num(m.section_count) + " needs " + num(m.section_count * kSectionBytes) +
                 " bytes of planes, payload has " + num(r.remaining())};
  for (int i = 0; i < m.section_count; ++i) r(m.sections[i]);
  return Message{m};
}

Result<Message> get_node_diff(Reader& r) {
  NodeDiff m;
  m.frame = r.u32();
  const uint64_t added = r.u32(), removed = r.u32();
  const uint64_t need = (added + removed) * 4;  // no overflow in 64 bits
  if (need != r.remaining())
    return Error{"frame " + num(m.frame) + ": counts " + num(added) + " added + " + num(removed) +
                 " removed need " + num(need) + " bytes, payload has " + num(r.remaining())};
  r.ids(m.added, added);
  r.ids(m.removed, removed);
  return Message{std::move(m)};
}

Result<Message> get_bye(Reader& r) {
  auto reason = get_str(r, "reason");
  if (!reason) return Error{reason.error()};
  return Message{Bye{std::move(*reason)}};
}

Result<Message> get_proof(Reader& r) {
  Proof m;
  r(m.mac);
  return Message{m};
}

}  // namespace

std::string_view type_name(Type t) {
  switch (t) {
    case Type::hello: return "hello";
    case Type::camera: return "camera";
    case Type::node_diff: return "node_diff";
    case Type::end_of_frame: return "end_of_frame";
    case Type::bye: return "bye";
    case Type::proof: return "proof";
    case Type::resync: return "resync";
  }
  return "unknown";
}

std::string_view role_name(Role r) {
  switch (r) {
    case Role::switch_node: return "switch_node";
    case Role::render_client: return "render_client";
    case Role::tool: return "tool";
  }
  return "unknown";
}

Type type_of(const Message& m) { return static_cast<Type>(m.index() + 1); }

bool Camera::operator==(const Camera& o) const {
  auto fixed = [](const Camera& c) {
    return std::tie(c.frame, c.eye[0], c.eye[1], c.eye[2], c.orientation[0], c.orientation[1], c.orientation[2],
                    c.orientation[3], c.fovy_rad, c.aspect, c.near_dist, c.far_dist, c.viewport_width_px,
                    c.viewport_height_px, c.occlusion, c.section_count);
  };
  if (fixed(*this) != fixed(o)) return false;
  for (int i = 0; i < section_count && i < 6; ++i)
    for (int k = 0; k < 4; ++k)
      if (sections[i][k] != o.sections[i][k]) return false;
  return true;
}

std::optional<std::string> invalid_reason(const Message& m) {
  auto e = std::visit([](const auto& msg) { return check(msg); }, m);
  if (e) return std::string(type_name(type_of(m))) + ": " + *e;
  return std::nullopt;
}

std::vector<uint8_t> encode(const Message& m) {
  std::vector<uint8_t> out;
  Writer w(out);
  w.u16(static_cast<uint16_t>(type_of(m)));
  w.u32(0);  // patched below
  std::visit([&](const auto& msg) { put(w, msg); }, m);
  const uint32_t payload = static_cast<uint32_t>(out.size() - kHeaderBytes);
  for (int i = 0; i < 4; ++i) out[2 + i] = static_cast<uint8_t>(payload >> (8 * i));
  return out;
}

Result<FrameHeader> decode_header(std::span<const uint8_t> bytes) {
  if (bytes.size() < kHeaderBytes)
    return Error{"truncated header: " + num(bytes.size()) + " of " + num(kHeaderBytes) + " bytes"};
  Reader r(bytes.first(kHeaderBytes));
  const uint16_t type = r.u16();
  const uint32_t payload_bytes = r.u32();
  if (!known_type(type)) return Error{"unknown message type " + num(type)};
  if (auto e = check_bounds(static_cast<Type>(type), payload_bytes)) return Error{*e};
  return FrameHeader{static_cast<Type>(type), payload_bytes};
}

Result<Message> decode_payload(Type type, std::span<const uint8_t> payload) {
  if (!known_type(static_cast<uint16_t>(type)))
    return Error{"unknown message type " + num(static_cast<uint16_t>(type))};
  if (auto e = check_bounds(type, payload.size())) return Error{*e};
  Reader r(payload);
  Result<Message> m = [&]() -> Result<Message> {
    switch (type) {
      case Type::hello: return get_hello(r);
      case Type::camera: return get_camera(r);
      case Type::node_diff: return get_node_diff(r);
      case Type::end_of_frame: return get_fields<EndOfFrame>(r, end_of_frame_fields);
      case Type::bye: return get_bye(r);
      case Type::proof: return get_proof(r);
      case Type::resync: return get_fields<Resync>(r, resync_fields);
    }
    return Error{"unreachable"};
  }();
  if (!m) return Error{std::string(type_name(type)) + ": " + m.error()};
  if (auto e = invalid_reason(*m)) return Error{*e};
  return m;
}

Result<Message> decode(std::span<const uint8_t> frame) {
  auto h = decode_header(frame);
  if (!h) return Error{h.error()};
  const size_t have = frame.size() - kHeaderBytes;
  const std::string what = std::string(type_name(h->type)) + " payload";
  if (have < h->payload_bytes)
    return Error{"truncated frame: " + num(have) + " of " + num(h->payload_bytes) + " " + what +
                 " bytes"};
  if (have > h->payload_bytes)
    return Error{"trailing bytes: " + num(have - h->payload_bytes) + " after a " +
                 num(h->payload_bytes) + "-byte " + what};
  return decode_payload(h->type, frame.subspan(kHeaderBytes));
}

std::vector<uint8_t> proof_input(ProofDirection d, const Hello& prover, const Hello& verifier) {
  const std::string_view label =
      d == ProofDirection::connector ? "occswitch proof v1 connector" : "occswitch proof v1 acceptor";
  std::vector<uint8_t> out(label.begin(), label.end());
  Writer w(out);
  w(prover.role, prover.node_id, verifier.role, verifier.node_id, verifier.nonce, prover.nonce);
  return out;
}

std::vector<NodeDiff> chunk_node_diff(uint32_t frame, std::span<const uint32_t> added,
                                      std::span<const uint32_t> removed, uint32_t max_ids) {
  if (max_ids < 1 || max_ids > kMaxDiffIds)
    throw std::invalid_argument("chunk_node_diff: max_ids " + num(max_ids) + " outside [1, " +
                                num(kMaxDiffIds) + "]");
  std::vector<NodeDiff> out;
  size_t a = 0, r = 0;
  while (a < added.size() || r < removed.size()) {
    NodeDiff d;
    d.frame = frame;
    const size_t take_a = std::min<size_t>(max_ids, added.size() - a);
    const size_t take_r = std::min<size_t>(max_ids - take_a, removed.size() - r);
    d.added.assign(added.begin() + a, added.begin() + a + take_a);
    d.removed.assign(removed.begin() + r, removed.begin() + r + take_r);
    a += take_a;
    r += take_r;
    out.push_back(std::move(d));
  }
  return out;
}

}  // namespace occ::wire
