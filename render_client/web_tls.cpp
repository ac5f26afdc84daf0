#include "render_client/web_tls.hpp"

#include <openssl/evp.h>
#include <openssl/rand.h>
#include <openssl/ssl.h>
#include <openssl/x509v3.h>

#include <cstdio>
#include <fstream>
#include <iostream>
#include <memory>

#include "common/error.hpp"

namespace occ {

namespace ssl = boost::asio::ssl;

namespace {

using Key = std::unique_ptr<EVP_PKEY, decltype(&EVP_PKEY_free)>;
using Cert = std::unique_ptr<X509, decltype(&X509_free)>;

void check(bool ok, const char* what) {
  if (!ok) throw InputError(std::string("--web ,tls=self-signed: ") + what + " failed");
}

void add_alt_names(X509* x) {
  X509V3_CTX v3;
  X509V3_set_ctx_nodb(&v3);
  X509V3_set_ctx(&v3, x, x, nullptr, nullptr, 0);
  X509_EXTENSION* ext = X509V3_EXT_conf_nid(nullptr, &v3, NID_subject_alt_name, "DNS:localhost,IP:127.0.0.1,IP:::1");
  check(ext != nullptr, "subjectAltName");
  X509_add_ext(x, ext, -1);
  X509_EXTENSION_free(ext);
}

// A certificate for localhost, valid from an hour ago for 30 days, signed by its own key.
Cert self_signed(EVP_PKEY* key) {
  Cert x(X509_new(), X509_free);
  check(x != nullptr, "X509_new");
  uint32_t serial = 0;
  check(RAND_bytes(reinterpret_cast<unsigned char*>(&serial), sizeof serial) == 1, "RAND_bytes");
  X509_set_version(x.get(), 2);
  ASN1_INTEGER_set(X509_get_serialNumber(x.get()), long(serial >> 1));
  X509_gmtime_adj(X509_getm_notBefore(x.get()), -3600);
  X509_gmtime_adj(X509_getm_notAfter(x.get()), 30L * 24 * 3600);
  X509_set_pubkey(x.get(), key);
  X509_NAME* name = X509_get_subject_name(x.get());
  X509_NAME_add_entry_by_txt(name, "CN", MBSTRING_ASC, reinterpret_cast<const unsigned char*>("localhost"), -1, -1, 0);
  X509_set_issuer_name(x.get(), name);
  add_alt_names(x.get());
  check(X509_sign(x.get(), key, EVP_sha256()) > 0, "X509_sign");
  return x;
}

std::string fingerprint(X509* x) {
  unsigned char md[EVP_MAX_MD_SIZE];
  unsigned int n = 0;
  X509_digest(x, EVP_sha256(), md, &n);
  std::string s;
  char b[4];
  for (unsigned int i = 0; i < n; ++i) {
    std::snprintf(b, sizeof b, i ? ":%02X" : "%02X", md[i]);
    s += b;
  }
  return s;
}

}  // namespace

ssl::context make_tls_context(const std::string& spec) {
  ssl::context ctx(ssl::context::tls_server);
  ctx.set_options(ssl::context::default_workarounds | ssl::context::no_sslv2 | ssl::context::no_sslv3 |
                  ssl::context::no_tlsv1 | ssl::context::no_tlsv1_1);
  if (spec == "self-signed") {
    Key key(EVP_EC_gen("P-256"), EVP_PKEY_free);
    check(key != nullptr, "EVP_EC_gen");
    const Cert x = self_signed(key.get());
    check(SSL_CTX_use_certificate(ctx.native_handle(), x.get()) == 1, "SSL_CTX_use_certificate");
    check(SSL_CTX_use_PrivateKey(ctx.native_handle(), key.get()) == 1, "SSL_CTX_use_PrivateKey");
    std::cerr << "render_client: web: self-signed certificate for localhost, SHA-256 " << fingerprint(x.get()) << "\n";
    return ctx;
  }
  const size_t colon = spec.find(':');
  const std::string cert = spec.substr(0, colon), key = spec.substr(colon + 1);
  for (const std::string& f : {cert, key})
    if (!std::ifstream(f)) throw InputError("--web ,tls='" + spec + "': cannot read '" + f + "'");
  boost::system::error_code ec;
  ctx.use_certificate_chain_file(cert, ec);
  if (ec) throw InputError("--web ,tls='" + spec + "': certificate '" + cert + "': " + ec.message());
  ctx.use_private_key_file(key, ssl::context::pem, ec);
  if (ec) throw InputError("--web ,tls='" + spec + "': key '" + key + "': " + ec.message());
  if (SSL_CTX_check_private_key(ctx.native_handle()) != 1)
    throw InputError("--web ,tls='" + spec + "': the key does not match the certificate");
  return ctx;
}

}  // namespace occ
