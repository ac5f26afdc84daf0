// Cluster membership (docs/security.md): a shared secret key, proven in the handshake by
// HMAC-SHA256 challenge-response over fresh nonces (the messages and the MAC'd bytes are in
// protocol/wire.hpp). The cryptography is OpenSSL's libcrypto (HMAC, RAND_bytes, CRYPTO_memcmp);
// nothing here is home-made crypto.
#pragma once
#include <array>
#include <string>
#include <string_view>
#include <vector>

#include "protocol/result.hpp"
#include "protocol/wire.hpp"

namespace occ::net {

class ClusterKey {
 public:
  static constexpr size_t kMinBytes = 32;    // e.g. `openssl rand -hex 32` gives 64
  static constexpr size_t kMaxBytes = 4096;

  // Reads a key file (--cluster-key-file): its bytes, one trailing "\n" or "\r\n" removed, are
  // the key. Errors name the file: missing, unreadable, empty, shorter than kMinBytes, longer
  // than kMaxBytes.
  static Result<ClusterKey> load(const std::string& path);
  // A key from bytes already in memory (tests); the same length rules.
  static Result<ClusterKey> from_bytes(std::string bytes, const std::string& what = "key");

  ClusterKey(ClusterKey&&) noexcept;
  ClusterKey& operator=(ClusterKey&&) noexcept;
  ClusterKey(const ClusterKey&);
  ClusterKey& operator=(const ClusterKey&);
  ~ClusterKey();  // wipes the bytes (OPENSSL_cleanse)

  // HMAC-SHA256(key, wire::proof_input(d, prover, verifier)).
  wire::Proof prove(wire::ProofDirection d, const wire::Hello& prover, const wire::Hello& verifier) const;
  // Whether `p` is that MAC (compared in constant time).
  bool verify(const wire::Proof& p, wire::ProofDirection d, const wire::Hello& prover,
              const wire::Hello& verifier) const;

  // A 32-byte subkey for one purpose: HKDF-SHA256 (RFC 5869) of the key, no salt, info = label.
  // The TLS links use one as their pre-shared key (protocol/net/tls.hpp), so the raw key serves
  // only the handshake MAC. The caller wipes the result (OPENSSL_cleanse) when done; throws
  // std::runtime_error if OpenSSL fails.
  std::array<unsigned char, 32> derive(std::string_view label) const;

 private:
  explicit ClusterKey(std::vector<unsigned char> bytes) : bytes_(std::move(bytes)) {}
  std::vector<unsigned char> bytes_;
};

// kNonceBytes from OpenSSL's CSPRNG (RAND_bytes); throws std::runtime_error if it fails.
wire::Nonce random_nonce();

}  // namespace occ::net
