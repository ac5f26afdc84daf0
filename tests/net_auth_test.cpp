// The cluster key (protocol/net/auth.hpp): key files and their errors, and the HMAC proofs of the
// handshake's challenge-response (right key accepted; wrong key, replayed or tampered proof, or
// a proof for the other direction refused). The exchange over real connections is in
// net_transport_test ("Handshake" with a key).
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include <gtest/gtest.h>
#include <openssl/evp.h>
#include <openssl/hmac.h>

#include "protocol/net/auth.hpp"

using namespace occ;
using wire::ProofDirection;
namespace fs = std::filesystem;

namespace {

fs::path temp_dir() {
  const fs::path d = fs::temp_directory_path() / ("occ_auth_test_" + std::to_string(::getpid()));
  fs::create_directories(d);
  return d;
}

std::string write(const fs::path& p, const std::string& bytes) {
  std::ofstream(p, std::ios::binary) << bytes;
  return p.string();
}

std::string load_error(const std::string& path) {
  auto k = net::ClusterKey::load(path);
  return k ? "<loaded>" : k.error();
}

net::ClusterKey key(const std::string& text) { return *net::ClusterKey::from_bytes(text); }

// A render client (connector) and switch node 1 (acceptor), each with a fresh nonce.
struct Exchange {
  wire::Hello client, node;
  Exchange() {
    client.role = wire::Role::render_client;
    node.role = wire::Role::switch_node;
    node.node_id = 1;
    client.auth = node.auth = wire::Auth::cluster_key;
    client.nonce = net::random_nonce();
    node.nonce = net::random_nonce();
  }
};

const std::string kKey = "0123456789abcdef0123456789abcdef";  // 32 bytes: the minimum

}  // namespace

TEST(ClusterKeyFile, BadFilesGetOneErrorNamingTheFile) {
  const fs::path d = temp_dir();
  EXPECT_EQ(load_error((d / "missing.key").string()),
            "cluster key file '" + (d / "missing.key").string() + "': No such file or directory");
  EXPECT_EQ(load_error(write(d / "empty.key", "")), "cluster key file '" + (d / "empty.key").string() + "' is empty");
  EXPECT_EQ(load_error(write(d / "newline.key", "\n")),
            "cluster key file '" + (d / "newline.key").string() + "' is empty");
  EXPECT_EQ(load_error(write(d / "short.key", "0123456789abcdef0123456789abcde\n")),
            "cluster key file '" + (d / "short.key").string() +
                "' is too short: 31 bytes, at least 32 needed (e.g. `openssl rand -hex 32 > FILE`)");
  EXPECT_EQ(load_error(write(d / "long.key", std::string(5000, 'x'))),
            "cluster key file '" + (d / "long.key").string() + "' is too long: more than 4096 bytes");
  EXPECT_EQ(load_error(d.string()), "cluster key file '" + d.string() + "' is a directory");
  // Unreadable: only testable when not root (root reads mode 000 files).
  const std::string locked = write(d / "locked.key", kKey);
  ::chmod(locked.c_str(), 0);
  if (::geteuid() != 0) {
    EXPECT_EQ(load_error(locked), "cluster key file '" + locked + "': Permission denied");
  }
  EXPECT_EQ(load_error(write(d / "ok.key", kKey + "\n")), "<loaded>");
  fs::remove_all(d);
}

TEST(ClusterKeyFile, OneTrailingNewlineIsNotPartOfTheKey) {
  const fs::path d = temp_dir();
  Exchange x;
  const auto plain = net::ClusterKey::load(write(d / "a.key", kKey));
  const auto lf = net::ClusterKey::load(write(d / "b.key", kKey + "\n"));
  const auto crlf = net::ClusterKey::load(write(d / "c.key", kKey + "\r\n"));
  const auto other = net::ClusterKey::load(write(d / "d.key", kKey + " "));
  ASSERT_TRUE(plain && lf && crlf && other);
  const wire::Proof p = plain->prove(ProofDirection::connector, x.client, x.node);
  EXPECT_TRUE(lf->verify(p, ProofDirection::connector, x.client, x.node));
  EXPECT_TRUE(crlf->verify(p, ProofDirection::connector, x.client, x.node));
  EXPECT_FALSE(other->verify(p, ProofDirection::connector, x.client, x.node));
  fs::remove_all(d);
}

TEST(ClusterKeyProof, IsHmacSha256OfTheDocumentedInput) {
  // The expected value computed independently (Python's hmac):
  //   hmac.new(b'0123456789abcdef0123456789abcdef', b'occswitch proof v1 connector' + bytes([1, 0, 0, 1])
  //            + bytes(32 * [0xaa]) + bytes(32 * [0xcc]), hashlib.sha256).hexdigest()
  wire::Hello c, a;
  c.role = wire::Role::render_client;
  a.role = wire::Role::switch_node;
  a.node_id = 1;
  c.nonce.fill(0xcc);
  a.nonce.fill(0xaa);
  const wire::Proof p = key(kKey).prove(ProofDirection::connector, c, a);
  std::string hex;
  for (uint8_t b : p.mac) {
    const char* d = "0123456789abcdef";
    hex += d[b >> 4];
    hex += d[b & 15];
  }
  EXPECT_EQ(hex, "65e38876a6f9276758f71fea3048ce7a94a16d887eb06650716c2c10bf1154ec");
}

TEST(ClusterKeyProof, TheRightKeyIsAcceptedInBothDirections) {
  Exchange x;
  const net::ClusterKey a = key(kKey), b = key(kKey);
  EXPECT_TRUE(b.verify(a.prove(ProofDirection::connector, x.client, x.node), ProofDirection::connector, x.client, x.node));
  EXPECT_TRUE(a.verify(b.prove(ProofDirection::acceptor, x.node, x.client), ProofDirection::acceptor, x.node, x.client));
}

TEST(ClusterKeyProof, AWrongKeyIsRefused) {
  Exchange x;
  const wire::Proof p = key(kKey).prove(ProofDirection::connector, x.client, x.node);
  for (const std::string& other : {std::string("1123456789abcdef0123456789abcdef"), kKey + "0", kKey.substr(0, 31) + "F"})
    EXPECT_FALSE(key(other).verify(p, ProofDirection::connector, x.client, x.node)) << other;
}

TEST(ClusterKeyProof, AReplayedProofIsRefusedUnderAFreshChallenge) {
  const net::ClusterKey k = key(kKey);
  Exchange first;
  const wire::Proof recorded = k.prove(ProofDirection::connector, first.client, first.node);
  Exchange second = first;
  second.node.nonce = net::random_nonce();  // the verifier's new challenge
  EXPECT_NE(second.node.nonce, first.node.nonce);
  EXPECT_FALSE(k.verify(recorded, ProofDirection::connector, second.client, second.node));
}

TEST(ClusterKeyProof, ATamperedProofOrTranscriptIsRefused) {
  const net::ClusterKey k = key(kKey);
  Exchange x;
  const wire::Proof p = k.prove(ProofDirection::connector, x.client, x.node);
  for (size_t i = 0; i < p.mac.size(); ++i)
    for (uint8_t bit : {uint8_t(1), uint8_t(0x80)}) {
      wire::Proof t = p;
      t.mac[i] ^= bit;
      EXPECT_FALSE(k.verify(t, ProofDirection::connector, x.client, x.node)) << "byte " << i;
    }
  Exchange y = x;
  y.client.nonce[0] ^= 1;  // the prover's nonce
  EXPECT_FALSE(k.verify(p, ProofDirection::connector, y.client, y.node));
  y = x;
  y.client.node_id = 1;  // who it claims to be
  EXPECT_FALSE(k.verify(p, ProofDirection::connector, y.client, y.node));
  y = x;
  y.node.role = wire::Role::render_client;  // whom it proves to
  EXPECT_FALSE(k.verify(p, ProofDirection::connector, y.client, y.node));
}

TEST(ClusterKeyProof, AProofForOneDirectionDoesNotServeForTheOther) {
  // Reflection: the connector's proof, sent back as if it were the acceptor's.
  const net::ClusterKey k = key(kKey);
  Exchange x;
  const wire::Proof p = k.prove(ProofDirection::connector, x.client, x.node);
  EXPECT_FALSE(k.verify(p, ProofDirection::acceptor, x.client, x.node));
  wire::Hello same = x.client;  // a peer claiming to be the prover itself, with its nonce
  EXPECT_FALSE(k.verify(p, ProofDirection::acceptor, same, x.client));
}

TEST(ClusterKeyProof, NoncesAreFreshAndNotZero) {
  const wire::Nonce a = net::random_nonce(), b = net::random_nonce();
  EXPECT_NE(a, b);
  EXPECT_NE(a, wire::Nonce{});
}

TEST(ClusterKeyDerive, IsHkdfSha256WithoutSaltOfTheLabel) {
  // RFC 5869 by hand: PRK = HMAC(32 zero bytes, key); the first 32 output bytes = HMAC(PRK, info | 0x01).
  const std::string label = "some purpose";
  unsigned char zeros[32] = {}, prk[32], okm[32];
  unsigned int len = 0;
  ASSERT_TRUE(HMAC(EVP_sha256(), zeros, 32, reinterpret_cast<const unsigned char*>(kKey.data()), kKey.size(), prk, &len));
  std::string info = label + '\x01';
  ASSERT_TRUE(HMAC(EVP_sha256(), prk, 32, reinterpret_cast<const unsigned char*>(info.data()), info.size(), okm, &len));
  const auto derived = key(kKey).derive(label);
  EXPECT_TRUE(std::equal(derived.begin(), derived.end(), okm));
  // Another label or another key gives another subkey; neither is the key itself.
  EXPECT_NE(key(kKey).derive("other purpose"), derived);
  EXPECT_NE(key(kKey + "x").derive(label), derived);
  EXPECT_FALSE(std::equal(derived.begin(), derived.end(), reinterpret_cast<const unsigned char*>(kKey.data())));
}
