// TLS 1.3 for the links of a keyed cluster (docs/security.md), used by the Connection
// (transport.cpp) only: Boost.Asio's ssl::stream over OpenSSL, and nothing of it reaches
// transport.hpp.
//
// Both sides hold the same external pre-shared key, ClusterKey::derive(kPskLabel), under the
// identity kPskIdentity; there are no certificates. TLS 1.3 only, one cipher suite
// (TLS_AES_128_GCM_SHA256), PSK with (EC)DHE key exchange (psk_dhe_ke: forward secrecy), no
// session tickets. A peer without the key cannot complete the handshake: it has no certificate
// to fall back on, and a wrong key fails the PSK binder. After the handshake every byte of the
// stream is encrypted and authenticated (AES-GCM): an altered byte fails the record's tag.
#pragma once
#include <array>
#include <memory>
#include <span>
#include <string>

#include "protocol/net/counted_socket.hpp"

#include <boost/asio/ssl.hpp>

namespace occ::net {
class ClusterKey;
}

namespace occ::net::tls {

inline constexpr char kPskLabel[] = "occswitch tls13 external psk v1";
inline constexpr char kPskIdentity[] = "occswitch-cluster";

using Stream = boost::asio::ssl::stream<CountedSocket&>;

// One side's TLS context with the PSK (wiped on destruction). It must outlive the streams made
// with it and must not move (OpenSSL's callbacks find the PSK through it).
class Context {
 public:
  // acceptor: the side that accepted the TCP connection (the TLS server). Throws
  // std::runtime_error when OpenSSL refuses a setting.
  Context(const ClusterKey& key, bool acceptor);
  ~Context();
  Context(const Context&) = delete;
  Context& operator=(const Context&) = delete;

  boost::asio::ssl::context& native() { return ctx_; }
  const std::array<unsigned char, 32>& psk() const { return psk_; }

 private:
  boost::asio::ssl::context ctx_;
  std::array<unsigned char, 32> psk_;
};

// Why a TLS handshake failed, for the connection's one error line, with what it most likely
// means (no key on the peer, another key, a peer that offered no PSK).
std::string handshake_failure(const asio_names::error_code& ec);
// Why reading the TLS stream failed; an altered record is named as such ("integrity check").
// Empty when `ec` is not a TLS error (the caller describes it as a plain read error).
std::string read_failure(const asio_names::error_code& ec);
// What the acceptor sends a peer that spoke no TLS at all (a keyless member, a stranger), so it can
// tell that a cluster key is needed: a bare TLS alert, nothing of the cluster. Empty for other
// failures (OpenSSL has sent its own alert then, if any).
std::span<const uint8_t> plaintext_refusal(const asio_names::error_code& ec);
// Whether bytes a keyless connection received look like a TLS record (a keyed peer).
bool looks_like_tls(std::span<const uint8_t> first_bytes);

}  // namespace occ::net::tls
