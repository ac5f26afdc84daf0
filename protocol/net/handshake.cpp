// The wire handshake (transport.hpp, handshake()): hellos, the expectations, the cluster key's
// HMAC challenge-response. Uses only Connection's public calls.
#include "protocol/net/auth.hpp"
#include "protocol/net/deadline.hpp"
#include "protocol/net/transport.hpp"

#include "common/hash.hpp"

namespace occ::net {

namespace {

std::optional<std::string> hello_mismatch(const wire::Hello& ours, const wire::Hello& peer,
                                          const PeerExpectation& expect) {
  auto differs = [](const char* what, auto a, auto b, bool as_hex) -> std::optional<std::string> {
    if (a == b) return std::nullopt;
    auto show = [&](uint64_t v) { return as_hex ? hex(v) : std::to_string(v); };
    return std::string(what) + " mismatch: ours " + show(a) + ", peer has " + show(b);
  };
  if (auto e = differs("scene fingerprint", ours.scene_fingerprint, peer.scene_fingerprint, true))
    return e;
  if (auto e = differs("build parameter arity", ours.arity, peer.arity, false)) return e;
  if (auto e = differs("build parameter leaf_items", ours.leaf_items, peer.leaf_items, false))
    return e;
  if (auto e = differs("build parameter cluster_triangles", ours.cluster_triangles,
                       peer.cluster_triangles, false))
    return e;
  if (auto e = differs("config hash", ours.config_hash, peer.config_hash, true)) return e;
  if (expect.role && *expect.role != peer.role)
    return "unexpected role " + std::string(wire::role_name(peer.role)) + " (expected " +
           std::string(wire::role_name(*expect.role)) + ")";
  if (expect.node_id && *expect.node_id != peer.node_id)
    return "unexpected node id " + std::to_string(peer.node_id) + " (expected " +
           std::to_string(*expect.node_id) + ")";
  if (expect.same_viewport && (ours.viewport_width_px != peer.viewport_width_px ||
                               ours.viewport_height_px != peer.viewport_height_px))
    return "viewport mismatch: ours " + std::to_string(ours.viewport_width_px) + "x" +
           std::to_string(ours.viewport_height_px) + ", peer has " +
           std::to_string(peer.viewport_width_px) + "x" + std::to_string(peer.viewport_height_px);
  return std::nullopt;
}

// Whether the two hellos' auth settings can meet: both with a key or both without.
std::optional<std::string> auth_mismatch(bool keyed, const wire::Hello& peer) {
  const bool peer_keyed = peer.auth == wire::Auth::cluster_key;
  if (keyed && !peer_keyed)
    return std::string("cluster key: the peer has none (it was started without --cluster-key-file), this process "
                       "requires one");
  if (!keyed && peer_keyed)
    return std::string("cluster key: the peer requires one (--cluster-key-file), this process has none");
  return std::nullopt;
}

// Said by the side that checked the proof (and, in its Bye, to the side that sent it).
std::string wrong_key(const wire::Hello& prover) {
  return "cluster key mismatch: the proof of " + std::string(wire::role_name(prover.role)) + " " +
         std::to_string(prover.node_id) + " (\"" + prover.name + "\") does not verify: another key";
}

}  // namespace

Result<wire::Hello> handshake(Connection& conn, const wire::Hello& mine_in,
                              const PeerExpectation& expect, Millis timeout) {
  auto fail = [&](const Error& e) -> Result<wire::Hello> {
    conn.close_with_error(e.reason);
    return Error{"peer " + conn.peer() + ": " + e.reason, e.kind};
  };
  const auto deadline = deadline_after(timeout);
  // One message from the peer within the handshake's time; a Bye or failure ends it with its reason.
  auto next = [&](wire::Type type) -> Result<wire::Message> {
    const std::string what(wire::type_name(type));
    Received r = conn.receive(std::max(Millis(1), remaining_until(deadline)));
    switch (r.status) {
      case Received::Status::timeout:
        return Error{"no " + what + " within " + std::to_string(timeout.count()) + " ms"};
      case Received::Status::closed: return Error{r.reason, r.busy ? ErrorKind::busy : ErrorKind::other};
      case Received::Status::error: return Error{r.reason};
      case Received::Status::message: break;
    }
    if (wire::type_of(r.message) != type)
      return Error{"expected " + what + ", got " + std::string(wire::type_name(wire::type_of(r.message)))};
    return std::move(r.message);
  };
  // A connection that already ended (e.g. the peer's first bytes were garbage) reports why in
  // receive(); only a message we cannot send at all fails here.
  auto send = [&](const wire::Message& m) -> std::optional<std::string> {
    if (auto e = conn.send(m); e && conn.is_open()) return e;
    return std::nullopt;
  };
  const bool keyed = expect.key != nullptr;
  if (keyed != conn.encrypted())
    return fail(Error{keyed ? "a cluster key for the handshake but a connection without TLS (ConnectionOptions::key unset)"
                            : "a TLS connection but no cluster key for the handshake (PeerExpectation::key unset)"});
  wire::Hello mine = mine_in;
  mine.auth = keyed ? wire::Auth::cluster_key : wire::Auth::none;
  mine.nonce = keyed ? random_nonce() : wire::Nonce{};
  using wire::ProofDirection;

  if (!conn.accepted()) {  // the connector: hello, (its proof), then the acceptor's verdict
    if (auto e = send(mine)) return fail(Error{*e});
    auto m = next(wire::Type::hello);
    if (!m) return fail(Error{m.error(), m.error_kind()});
    const wire::Hello peer = std::get<wire::Hello>(*m);
    if (auto e = hello_mismatch(mine, peer, expect)) return fail(Error{*e});
    if (auto e = auth_mismatch(keyed, peer)) return fail(Error{*e});
    if (!keyed) return peer;
    if (peer.nonce == mine.nonce) return fail(Error{"cluster key: the peer's nonce is ours (reflected)"});
    if (auto e = send(expect.key->prove(ProofDirection::connector, mine, peer))) return fail(Error{*e});
    auto p = next(wire::Type::proof);
    if (!p) return fail(Error{p.error(), p.error_kind()});
    if (!expect.key->verify(std::get<wire::Proof>(*p), ProofDirection::acceptor, peer, mine))
      return fail(Error{wrong_key(peer)});
    return peer;
  }

  // The acceptor: the connector's hello first, then ours (or a refusal instead of our last message).
  auto m = next(wire::Type::hello);
  if (!m) return fail(Error{m.error(), m.error_kind()});
  const wire::Hello peer = std::get<wire::Hello>(*m);
  std::optional<std::string> wrong = hello_mismatch(mine, peer, expect);
  if (!wrong) wrong = auth_mismatch(keyed, peer);
  if (wrong) {  // our hello first, so the connector sees the difference and says so itself
    send(mine);
    return fail(Error{*wrong});
  }
  if (keyed) {
    if (auto e = send(mine)) return fail(Error{*e});
    auto p = next(wire::Type::proof);
    if (!p) return fail(Error{p.error(), p.error_kind()});
    if (!expect.key->verify(std::get<wire::Proof>(*p), ProofDirection::connector, peer, mine))
      return fail(Error{wrong_key(peer)});
  }
  if (expect.refuse)
    if (auto why = expect.refuse(peer)) return fail(Error{*why});
  if (auto e = send(keyed ? wire::Message{expect.key->prove(ProofDirection::acceptor, mine, peer)} : wire::Message{mine}))
    return fail(Error{*e});
  return peer;
}

}  // namespace occ::net
