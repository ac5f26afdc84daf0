// Fuzz-style decoder tests with fixed seeds (reproducible in CI). Property for every input: the
// decoder returns a value or a non-empty reason, never crashes (run under OCC_SANITIZE for
// memory errors), and whatever it accepts re-encodes to exactly the same bytes.
#include <random>

#include <gtest/gtest.h>

#include "protocol/wire.hpp"

using namespace occ::wire;

std::vector<Message> sample_messages();

namespace {

struct Tally {
  size_t accepted = 0, rejected = 0;
};

// Decodes one frame and checks the property; returns false (and records a failure) if violated.
void check_frame(const std::vector<uint8_t>& bytes, Tally& tally) {
  auto r = decode(bytes);
  if (r) {
    ++tally.accepted;
    ASSERT_EQ(encode(*r), bytes) << "accepted frame does not re-encode identically";
    ASSERT_FALSE(invalid_reason(*r));
  } else {
    ++tally.rejected;
    ASSERT_FALSE(r.error().empty());
  }
}

// A frame header with a known type and a length inside that type's bounds, followed by random
// payload bytes, so the input gets past the header checks into the payload decoders.
std::vector<uint8_t> random_plausible_frame(std::mt19937_64& rng) {
  static const uint32_t sizes[][2] = {{79, 143}, {100, 100}, {12, 200}, {68, 68},
                                      {2, 120},  {32, 32},   {12, 12}};
  static_assert(std::size(sizes) == kTypeCount);
  const uint16_t type = static_cast<uint16_t>(1 + rng() % kTypeCount);
  const auto [lo, hi] = sizes[type - 1];
  const uint32_t len = lo + static_cast<uint32_t>(rng() % (hi - lo + 1));
  std::vector<uint8_t> b = {static_cast<uint8_t>(type), 0};
  for (int i = 0; i < 4; ++i) b.push_back(static_cast<uint8_t>(len >> (8 * i)));
  for (uint32_t i = 0; i < len; ++i) b.push_back(static_cast<uint8_t>(rng()));
  // Random bytes rarely pass magic/version or UTF-8 checks: make half of them plausible.
  if (type == 1 && rng() % 2) {
    const uint8_t prefix[] = {'O', 'C', 'S', 'W', static_cast<uint8_t>(kProtocolVersion), 0, static_cast<uint8_t>(rng() % 3)};
    std::copy(std::begin(prefix), std::end(prefix), b.begin() + 6);
    const uint8_t auth = static_cast<uint8_t>(rng() % 2);  // with auth 0, the nonce must be zero
    b[6 + 44] = auth;
    if (auth == 0) std::fill(b.begin() + 6 + 45, b.begin() + 6 + 77, uint8_t(0));
    const uint16_t name = static_cast<uint16_t>(len - 79);
    b[6 + 77] = name & 0xff;
    b[6 + 78] = name >> 8;
    for (size_t i = 6 + 79; i < b.size(); ++i) b[i] = 'a' + rng() % 26;
  }
  if (type == 3 && rng() % 2) {  // consistent counts
    const uint32_t ids = (len - 12) / 4, added = ids ? static_cast<uint32_t>(rng() % (ids + 1)) : 0;
    b.resize(6 + 12 + 4 * ids);
    b[2] = static_cast<uint8_t>(12 + 4 * ids);
    b[3] = 0;
    for (int i = 0; i < 4; ++i) b[6 + 4 + i] = static_cast<uint8_t>(added >> (8 * i));
    for (int i = 0; i < 4; ++i) b[6 + 8 + i] = static_cast<uint8_t>((ids - added) >> (8 * i));
  }
  return b;
}

void mutate(std::vector<uint8_t>& b, std::mt19937_64& rng) {
  const int edits = 1 + static_cast<int>(rng() % 4);
  for (int e = 0; e < edits; ++e) {
    switch (rng() % 6) {
      case 0:  // flip a bit
        if (!b.empty()) b[rng() % b.size()] ^= static_cast<uint8_t>(1u << (rng() % 8));
        break;
      case 1:  // random byte
        if (!b.empty()) b[rng() % b.size()] = static_cast<uint8_t>(rng());
        break;
      case 2:  // truncate
        b.resize(rng() % (b.size() + 1));
        break;
      case 3:  // append junk
        for (int i = 1 + static_cast<int>(rng() % 8); i > 0; --i)
          b.push_back(static_cast<uint8_t>(rng()));
        break;
      case 4:  // interesting value into the header length or a count
        if (b.size() >= 6) {
          static const uint32_t values[] = {0, 1, 11, 12, 99, 100, 101, 0xffff, kMaxPayloadBytes,
                                            kMaxPayloadBytes + 1, 0x7fffffff, 0xffffffff};
          const uint32_t v = values[rng() % std::size(values)];
          const size_t at = b.size() >= 18 && rng() % 2 ? 6 + 4 * (rng() % 3) : 2;
          for (int i = 0; i < 4; ++i) b[at + i] = static_cast<uint8_t>(v >> (8 * i));
        }
        break;
      case 5:  // special doubles over an 8-byte field
        if (b.size() >= 14) {
          static const uint64_t values[] = {0x7ff8000000000000ULL, 0x7ff0000000000000ULL,
                                            0x8000000000000000ULL, 0, 0x0000000000000001ULL};
          const uint64_t v = values[rng() % std::size(values)];
          const size_t at = 6 + rng() % (b.size() - 13);
          for (int i = 0; i < 8; ++i) b[at + i] = static_cast<uint8_t>(v >> (8 * i));
        }
        break;
    }
  }
}

}  // namespace

TEST(WireFuzz, RandomBytesAreRejectedOrReencodeIdentically) {
  std::mt19937_64 rng(0x0c5e1);
  Tally tally;
  for (int i = 0; i < 100000; ++i) {
    std::vector<uint8_t> b;
    if (i % 2) {
      b.resize(rng() % 160);
      for (auto& x : b) x = static_cast<uint8_t>(rng());
    } else {
      b = random_plausible_frame(rng);
    }
    check_frame(b, tally);
    if (HasFatalFailure()) return;
  }
  EXPECT_EQ(tally.accepted + tally.rejected, 100000u);
  EXPECT_GT(tally.accepted, 1000u);  // the payload decoders were reached and passed
  EXPECT_GT(tally.rejected, 50000u);
}

TEST(WireFuzz, MutatedValidFramesAreRejectedOrReencodeIdentically) {
  std::mt19937_64 rng(0x5eed2);
  const auto samples = sample_messages();
  Tally tally;
  for (int i = 0; i < 100000; ++i) {
    auto b = encode(samples[rng() % samples.size()]);
    mutate(b, rng);
    check_frame(b, tally);
    if (HasFatalFailure()) return;
  }
  EXPECT_GT(tally.accepted, 1000u);
  EXPECT_GT(tally.rejected, 50000u);
}

// A stream reader built from the two streaming steps decodes every valid frame of a stream and
// stops with a reason at the first bad one.
TEST(WireFuzz, RandomStreamsDecodeFrameByFrameUntilTheFirstBadFrame) {
  std::mt19937_64 rng(0x57e4);
  const auto samples = sample_messages();
  for (int round = 0; round < 2000; ++round) {
    std::vector<uint8_t> stream;
    std::vector<Message> sent;
    for (int n = static_cast<int>(rng() % 20); n > 0; --n) {
      sent.push_back(samples[rng() % samples.size()]);
      const auto b = encode(sent.back());
      stream.insert(stream.end(), b.begin(), b.end());
    }
    const size_t valid_bytes = stream.size();
    for (int n = static_cast<int>(rng() % 64); n > 0; --n)
      stream.push_back(static_cast<uint8_t>(rng()));

    std::vector<Message> got;
    size_t pos = 0;
    std::string stop = "end of stream";
    while (pos < stream.size()) {
      const std::span<const uint8_t> rest(stream.data() + pos, stream.size() - pos);
      auto h = decode_header(rest);
      if (!h) {
        stop = h.error();
        break;
      }
      if (rest.size() - kHeaderBytes < h->payload_bytes) {
        stop = "truncated";
        break;
      }
      auto m = decode_payload(h->type, rest.subspan(kHeaderBytes, h->payload_bytes));
      if (!m) {
        stop = m.error();
        break;
      }
      got.push_back(std::move(*m));
      pos += kHeaderBytes + h->payload_bytes;
    }
    ASSERT_GE(got.size(), sent.size()) << "stopped early: " << stop;
    ASSERT_TRUE(std::equal(sent.begin(), sent.end(), got.begin()));
    ASSERT_GE(pos, valid_bytes);
    ASSERT_FALSE(stop.empty());
  }
}
