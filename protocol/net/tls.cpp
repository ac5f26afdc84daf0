#include "protocol/net/tls.hpp"

#include "protocol/net/auth.hpp"

#include <openssl/crypto.h>
#include <openssl/err.h>
#include <openssl/ssl.h>

#include <cstring>
#include <stdexcept>

namespace occ::net::tls {
using namespace asio_names;

namespace {

constexpr unsigned char kAes128GcmSha256[] = {0x13, 0x01};  // TLS_AES_128_GCM_SHA256 (RFC 8446 B.4)

// Where an SSL_CTX keeps its Context (not app_data: Boost.Asio's context owns that slot).
int context_index() {
  static const int index = SSL_CTX_get_ex_new_index(0, nullptr, nullptr, nullptr, nullptr);
  return index;
}

const Context& context_of(SSL* ssl) {
  return *static_cast<const Context*>(SSL_CTX_get_ex_data(SSL_get_SSL_CTX(ssl), context_index()));
}

// A resumption-style session that carries the external PSK for TLS 1.3 (OpenSSL's way to give
// one: SSL_CTX_set_psk_use_session_callback(3)). nullptr if OpenSSL refuses.
SSL_SESSION* psk_session(SSL* ssl) {
  const SSL_CIPHER* cipher = SSL_CIPHER_find(ssl, kAes128GcmSha256);
  SSL_SESSION* s = cipher ? SSL_SESSION_new() : nullptr;
  const auto& psk = context_of(ssl).psk();
  if (s && SSL_SESSION_set1_master_key(s, psk.data(), psk.size()) && SSL_SESSION_set_cipher(s, cipher) &&
      SSL_SESSION_set_protocol_version(s, TLS1_3_VERSION))
    return s;
  SSL_SESSION_free(s);
  return nullptr;
}

// The connector offers the PSK under kPskIdentity (md: the hash a HelloRetryRequest fixed, if any).
int use_psk(SSL* ssl, const EVP_MD* md, const unsigned char** id, size_t* id_len, SSL_SESSION** out) {
  *out = nullptr;
  SSL_SESSION* s = psk_session(ssl);
  if (!s) return 0;
  if (md && SSL_CIPHER_get_handshake_digest(SSL_SESSION_get0_cipher(s)) != md) {
    SSL_SESSION_free(s);  // cannot happen with one suite; offer nothing rather than a mismatch
    return 1;
  }
  *out = s;
  *id = reinterpret_cast<const unsigned char*>(kPskIdentity);
  *id_len = std::strlen(kPskIdentity);
  return 1;
}

// The acceptor knows one identity; any other gets no PSK (and, with no certificate, no handshake).
int find_psk(SSL* ssl, const unsigned char* id, size_t id_len, SSL_SESSION** out) {
  *out = nullptr;
  if (id_len != std::strlen(kPskIdentity) || std::memcmp(id, kPskIdentity, id_len) != 0) return 1;
  *out = psk_session(ssl);
  return *out ? 1 : 0;
}

bool is_tls_error(const error_code& ec) { return ec.category() == asio::error::get_ssl_category(); }
int reason_of(const error_code& ec) { return is_tls_error(ec) ? ERR_GET_REASON(ec.value()) : 0; }

}  // namespace

Context::Context(const ClusterKey& key, bool acceptor)
    : ctx_(acceptor ? asio::ssl::context::tls_server : asio::ssl::context::tls_client),
      psk_(key.derive(kPskLabel)) {
  SSL_CTX* c = ctx_.native_handle();
  const bool ok = SSL_CTX_set_min_proto_version(c, TLS1_3_VERSION) == 1 &&
                  SSL_CTX_set_max_proto_version(c, TLS1_3_VERSION) == 1 &&
                  SSL_CTX_set_ciphersuites(c, "TLS_AES_128_GCM_SHA256") == 1 &&
                  SSL_CTX_set_num_tickets(c, 0) == 1 && context_index() >= 0 && SSL_CTX_set_ex_data(c, context_index(), this) == 1;
  if (!ok) {
    OPENSSL_cleanse(psk_.data(), psk_.size());
    throw std::runtime_error("cannot set up TLS 1.3 with a pre-shared key (OpenSSL)");
  }
  // The wire protocol ends with an authenticated Bye, so a bare TCP EOF is reported as EOF
  // (the Connection calls it "closed without bye") rather than as a TLS error.
  SSL_CTX_set_options(c, SSL_OP_IGNORE_UNEXPECTED_EOF | SSL_OP_NO_TICKET);
  if (acceptor) SSL_CTX_set_psk_find_session_callback(c, find_psk);
  else SSL_CTX_set_psk_use_session_callback(c, use_psk);
}

Context::~Context() { OPENSSL_cleanse(psk_.data(), psk_.size()); }

std::string handshake_failure(const error_code& ec) {
  std::string meaning;
  switch (reason_of(ec)) {
    case SSL_R_BINDER_DOES_NOT_VERIFY:  // the acceptor checked the connector's PSK binder
      meaning = "cluster key mismatch: the peer has another key";
      break;
    case SSL_R_SSLV3_ALERT_ILLEGAL_PARAMETER:  // the connector, told so by the acceptor (OpenSSL's
    case SSL_R_TLSV1_ALERT_DECRYPT_ERROR:      // alert for a binder that does not verify)
      meaning = "cluster key mismatch: the peer rejected the PSK of our key (it has another key)";
      break;
    case SSL_R_WRONG_VERSION_NUMBER:
    case SSL_R_PACKET_LENGTH_TOO_LONG:
    case SSL_R_RECORD_TOO_SMALL:
      meaning = "the peer speaks no TLS: it has no cluster key (started without --cluster-key-file), this process has one";
      break;
    case SSL_R_NO_SHARED_CIPHER:
    case SSL_R_NO_SUITABLE_SIGNATURE_ALGORITHM:
    case SSL_R_MISSING_PSK_KEX_MODES_EXTENSION:
      meaning = "the peer offered no cluster-key PSK";
      break;
    case SSL_R_SSLV3_ALERT_HANDSHAKE_FAILURE:
      meaning = "the peer refused our offer (no cluster-key PSK in common)";
      break;
    default:
      if (ec == asio::error::eof || ec == asio::error::connection_reset || ec == asio::ssl::error::stream_truncated)
        meaning = "the peer closed the connection (a peer without the cluster key, or with another one, does)";
  }
  return "TLS handshake failed: " + (meaning.empty() ? ec.message() : meaning + " (" + ec.message() + ")");
}

std::string read_failure(const error_code& ec) {
  switch (reason_of(ec)) {
    case 0: return {};
    case SSL_R_DECRYPTION_FAILED_OR_BAD_RECORD_MAC:
      return "TLS integrity check failed: a record was altered on the way (" + ec.message() + ")";
    case SSL_R_SSLV3_ALERT_BAD_RECORD_MAC:
      return "TLS integrity check failed at the peer: it received a record altered on the way (" + ec.message() + ")";
    default: return "TLS error: " + ec.message();
  }
}

std::span<const uint8_t> plaintext_refusal(const error_code& ec) {
  // A TLS 1.2-framed fatal alert, protocol_version (70): what a peer that is not TLS at all gets
  // back (OpenSSL sends nothing to such a peer). Fixed bytes: no key, no hello, no fingerprint.
  static constexpr uint8_t kAlert[] = {21, 3, 3, 0, 2, 2, 70};
  if (reason_of(ec) != SSL_R_WRONG_VERSION_NUMBER) return {};
  return kAlert;
}

bool looks_like_tls(std::span<const uint8_t> b) {
  // A TLS record header: content type handshake (22) or alert (21), then version 3.x.
  return b.size() >= 2 && (b[0] == 22 || b[0] == 21) && b[1] == 3;
}

}  // namespace occ::net::tls
