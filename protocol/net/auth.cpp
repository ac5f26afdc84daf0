#include "protocol/net/auth.hpp"

#include <openssl/crypto.h>
#include <openssl/evp.h>
#include <openssl/hmac.h>
#include <openssl/kdf.h>
#include <openssl/rand.h>
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>

namespace occ::net {

Result<ClusterKey> ClusterKey::from_bytes(std::string bytes, const std::string& what) {
  if (bytes.size() >= 1 && bytes.back() == '\n') bytes.pop_back();
  if (bytes.size() >= 1 && bytes.back() == '\r') bytes.pop_back();
  Error e;
  if (bytes.empty())
    e.reason = what + " is empty";
  else if (bytes.size() < kMinBytes)
    e.reason = what + " is too short: " + std::to_string(bytes.size()) + " bytes, at least " +
               std::to_string(kMinBytes) + " needed (e.g. `openssl rand -hex 32 > FILE`)";
  else if (bytes.size() > kMaxBytes)
    e.reason = what + " is too long: more than " + std::to_string(kMaxBytes) + " bytes";
  std::vector<unsigned char> key(bytes.begin(), bytes.end());
  OPENSSL_cleanse(bytes.data(), bytes.size());
  if (!e.reason.empty()) {
    OPENSSL_cleanse(key.data(), key.size());
    return e;
  }
  return ClusterKey(std::move(key));
}

Result<ClusterKey> ClusterKey::load(const std::string& path) {
  const std::string what = "cluster key file '" + path + "'";
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) return Error{what + ": " + std::strerror(errno)};
  struct stat st{};
  if (::fstat(fd, &st) == 0 && S_ISDIR(st.st_mode)) {
    ::close(fd);
    return Error{what + " is a directory"};
  }
  std::string bytes;
  char buf[1024];
  for (;;) {
    const ssize_t n = ::read(fd, buf, sizeof buf);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) {
      const int err = errno;
      ::close(fd);
      OPENSSL_cleanse(bytes.data(), bytes.size());
      return Error{what + ": cannot read: " + std::strerror(err)};
    }
    if (n == 0) break;
    bytes.append(buf, size_t(n));
    if (bytes.size() > kMaxBytes + 2) break;  // too long either way (from_bytes says so)
  }
  ::close(fd);
  OPENSSL_cleanse(buf, sizeof buf);
  return from_bytes(std::move(bytes), what);
}

ClusterKey::ClusterKey(ClusterKey&&) noexcept = default;
ClusterKey& ClusterKey::operator=(ClusterKey&& o) noexcept {
  if (this != &o) {
    OPENSSL_cleanse(bytes_.data(), bytes_.size());
    bytes_ = std::move(o.bytes_);
  }
  return *this;
}
ClusterKey::ClusterKey(const ClusterKey&) = default;
ClusterKey& ClusterKey::operator=(const ClusterKey& o) {
  if (this != &o) {
    OPENSSL_cleanse(bytes_.data(), bytes_.size());
    bytes_ = o.bytes_;
  }
  return *this;
}
ClusterKey::~ClusterKey() { OPENSSL_cleanse(bytes_.data(), bytes_.size()); }

wire::Proof ClusterKey::prove(wire::ProofDirection d, const wire::Hello& prover, const wire::Hello& verifier) const {
  const std::vector<uint8_t> msg = wire::proof_input(d, prover, verifier);
  wire::Proof p;
  unsigned int len = 0;
  if (!HMAC(EVP_sha256(), bytes_.data(), int(bytes_.size()), msg.data(), msg.size(), p.mac.data(), &len) ||
      len != p.mac.size())
    throw std::runtime_error("HMAC-SHA256 failed (OpenSSL)");
  return p;
}

bool ClusterKey::verify(const wire::Proof& p, wire::ProofDirection d, const wire::Hello& prover,
                        const wire::Hello& verifier) const {
  const wire::Proof expected = prove(d, prover, verifier);
  return CRYPTO_memcmp(expected.mac.data(), p.mac.data(), p.mac.size()) == 0;
}

std::array<unsigned char, 32> ClusterKey::derive(std::string_view label) const {
  std::array<unsigned char, 32> out{};
  size_t len = out.size();
  EVP_PKEY_CTX* ctx = EVP_PKEY_CTX_new_id(EVP_PKEY_HKDF, nullptr);
  const bool ok = ctx && EVP_PKEY_derive_init(ctx) > 0 && EVP_PKEY_CTX_set_hkdf_md(ctx, EVP_sha256()) > 0 &&
                  EVP_PKEY_CTX_set1_hkdf_key(ctx, bytes_.data(), int(bytes_.size())) > 0 &&
                  EVP_PKEY_CTX_add1_hkdf_info(ctx, reinterpret_cast<const unsigned char*>(label.data()),
                                              int(label.size())) > 0 &&
                  EVP_PKEY_derive(ctx, out.data(), &len) > 0 && len == out.size();
  EVP_PKEY_CTX_free(ctx);
  if (!ok) throw std::runtime_error("HKDF-SHA256 failed (OpenSSL)");
  return out;
}

wire::Nonce random_nonce() {
  wire::Nonce n;
  if (RAND_bytes(n.data(), int(n.size())) != 1) throw std::runtime_error("RAND_bytes failed (OpenSSL): no nonce");
  return n;
}

}  // namespace occ::net
