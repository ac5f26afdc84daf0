// Visible-set algebra: diff, rebuild through the wire, hash, and desync detection.
#include <algorithm>
#include <random>
#include <set>
#include <stdexcept>
#include <unordered_set>

#include <gtest/gtest.h>

#include "protocol/visible_set.hpp"

using namespace occ;

namespace {

VisibleSet make_set(uint32_t id_limit, std::initializer_list<uint32_t> ids) {
  VisibleSet s(id_limit);
  for (uint32_t id : ids) s.insert(id);
  return s;
}

std::set<uint32_t> members(const VisibleSet& s) { return {s.ids().begin(), s.ids().end()}; }

// Round trip through the encoder and decoder, as the receiver would see it.
template <class T>
T over_the_wire(const T& m) {
  auto r = wire::decode(wire::encode(m));
  EXPECT_TRUE(r) << r.error();
  return std::get<T>(*r);
}

// Next visible set: drops a random fraction of the current ids and adds random new ones.
VisibleSet next_set(const VisibleSet& cur, std::mt19937_64& rng) {
  VisibleSet next = cur;
  const double drop = std::uniform_real_distribution<double>(0.0, 0.3)(rng);
  std::vector<uint32_t> ids(cur.ids().begin(), cur.ids().end());
  for (uint32_t id : ids)
    if (std::uniform_real_distribution<double>(0, 1)(rng) < drop) next.erase(id);
  for (int n = static_cast<int>(rng() % 400); n > 0; --n)
    next.insert(static_cast<uint32_t>(rng() % cur.id_limit()));
  if (rng() % 50 == 0) next.clear();  // e.g. the camera turned to face a wall
  return next;
}

}  // namespace

TEST(VisibleSet, InsertEraseContains) {
  VisibleSet s(10);
  EXPECT_TRUE(s.insert(3));
  EXPECT_FALSE(s.insert(3));
  EXPECT_TRUE(s.insert(9));
  EXPECT_TRUE(s.contains(3));
  EXPECT_FALSE(s.contains(4));
  EXPECT_FALSE(s.contains(1000));  // out of range is simply absent
  EXPECT_EQ(s.size(), 2u);
  EXPECT_TRUE(s.erase(3));
  EXPECT_FALSE(s.erase(3));
  EXPECT_EQ(members(s), (std::set<uint32_t>{9}));
  EXPECT_THROW(s.insert(10), std::out_of_range);
  s.clear();
  EXPECT_TRUE(s.empty());
  EXPECT_FALSE(s.contains(9));
}

TEST(VisibleSet, IncrementalHashEqualsSetHashAndIgnoresOrder) {
  std::mt19937_64 rng(11);
  VisibleSet s(100000);
  for (int step = 0; step < 20000; ++step) {
    const uint32_t id = static_cast<uint32_t>(rng() % 3000);
    if (rng() % 3) s.insert(id);
    else s.erase(id);
  }
  std::vector<uint32_t> ids(s.ids().begin(), s.ids().end());
  EXPECT_EQ(s.hash(), set_hash(ids));
  std::shuffle(ids.begin(), ids.end(), rng);
  EXPECT_EQ(set_hash(ids), s.hash());
  std::sort(ids.begin(), ids.end());
  VisibleSet rebuilt(100000);
  for (uint32_t id : ids) rebuilt.insert(id);
  EXPECT_EQ(rebuilt.hash(), s.hash());
  EXPECT_EQ(rebuilt, s);
  EXPECT_EQ(VisibleSet(5).hash(), set_hash({}));
}

TEST(VisibleSet, HashSeparatesNearlyEqualSets) {
  // Every set that differs from a base set by one id (added, removed or replaced) hashes
  // differently from the base and from each other.
  VisibleSet base(5000);
  for (uint32_t id = 0; id < 2000; id += 2) base.insert(id);
  std::unordered_set<uint64_t> hashes = {base.hash()};
  size_t variants = 0;
  for (uint32_t id = 0; id < 3000; ++id) {
    VisibleSet v = base;
    if (v.contains(id)) v.erase(id);
    else v.insert(id);
    hashes.insert(v.hash());
    ++variants;
    if (id % 2 == 0 && id + 1 < 5000) {
      v.insert(id + 1);  // replaced id -> id + 1: same size
      hashes.insert(v.hash());
      ++variants;
    }
  }
  EXPECT_EQ(hashes.size(), variants + 1);
}

TEST(VisibleSet, DiffSetsMatchesTheDefinition) {
  const VisibleSet prev = make_set(20, {1, 2, 3, 4, 10});
  const VisibleSet cur = make_set(20, {3, 4, 5, 6, 10, 19});
  const SetDiff d = diff_sets(prev, cur);
  EXPECT_EQ(std::set<uint32_t>(d.added.begin(), d.added.end()), (std::set<uint32_t>{5, 6, 19}));
  EXPECT_EQ(std::set<uint32_t>(d.removed.begin(), d.removed.end()), (std::set<uint32_t>{1, 2}));
  EXPECT_TRUE(diff_sets(cur, cur).added.empty());
  EXPECT_TRUE(diff_sets(cur, cur).removed.empty());
}

TEST(VisibleSet, RandomSequencesRebuiltThroughTheWireEqualTheTruth) {
  std::mt19937_64 rng(2003);
  const uint32_t id_limit = 20000;
  VisibleSet truth(id_limit), rebuilt(id_limit);
  DiffReceiver receiver;
  uint32_t frame = 0;
  for (int f = 0; f < 300; ++f) {
    frame += 1 + static_cast<uint32_t>(rng() % 2);  // a switch node receives every other frame
    const VisibleSet next = next_set(truth, rng);
    const SetDiff d = diff_sets(truth, next);
    const uint32_t b = 1 + static_cast<uint32_t>(rng() % 300);
    for (const auto& chunk : wire::chunk_node_diff(frame, d.added, d.removed, b))
      ASSERT_FALSE(receiver.on_diff(rebuilt, over_the_wire(chunk)));
    const auto eof = over_the_wire(make_end_of_frame(frame, d, next));
    EXPECT_EQ(eof.total_added, d.added.size());
    EXPECT_EQ(eof.visible_count, next.size());
    ASSERT_FALSE(receiver.on_end_of_frame(rebuilt, eof)) << "frame " << frame;
    truth = next;
    ASSERT_EQ(members(rebuilt), members(truth)) << "frame " << frame;
  }
  EXPECT_EQ(receiver.last_frame(), frame);
}

TEST(VisibleSet, ApplyRejectsImpossibleDiffsAndLeavesTheSetUnchanged) {
  VisibleSet s = make_set(100, {1, 2, 3});
  const uint64_t before = s.hash();
  EXPECT_EQ(apply(s, wire::NodeDiff{5, {10}, {1, 4}}).value_or(""),
            "frame 5: removing id 4 that is not in the set");
  EXPECT_EQ(apply(s, wire::NodeDiff{5, {10, 2}, {1}}).value_or(""),
            "frame 5: adding id 2 that is already in the set");
  EXPECT_EQ(apply(s, wire::NodeDiff{5, {10, 100}, {}}).value_or(""),
            "frame 5: adding id 100 out of range (100 nodes)");
  EXPECT_EQ(apply(s, wire::NodeDiff{5, {}, {3, 3}}).value_or(""),
            "frame 5: removing id 3 that is not in the set");
  EXPECT_EQ(s.hash(), before);
  EXPECT_EQ(members(s), (std::set<uint32_t>{1, 2, 3}));
  EXPECT_FALSE(apply(s, wire::NodeDiff{5, {10, 11}, {1}}));
  EXPECT_EQ(members(s), (std::set<uint32_t>{2, 3, 10, 11}));
}

TEST(VisibleSet, VerifyReportsTheFrameAndBothHashes) {
  const VisibleSet truth = make_set(50, {1, 2, 3});
  VisibleSet wrong = make_set(50, {1, 2, 4});
  const auto eof = make_end_of_frame(7, SetDiff{}, truth);
  EXPECT_FALSE(verify(eof, truth));
  const std::string err = verify(eof, wrong).value_or("");
  EXPECT_NE(err.find("desync at frame 7"), std::string::npos) << err;
  char ours[32], theirs[32];
  std::snprintf(ours, sizeof ours, "0x%016llx", static_cast<unsigned long long>(wrong.hash()));
  std::snprintf(theirs, sizeof theirs, "0x%016llx", static_cast<unsigned long long>(truth.hash()));
  EXPECT_NE(err.find(ours), std::string::npos) << err;
  EXPECT_NE(err.find(theirs), std::string::npos) << err;
  wrong.insert(5);
  EXPECT_NE(verify(eof, wrong).value_or("").find("4 ids"), std::string::npos);
}

TEST(DiffReceiver, DetectsALostChunk) {
  VisibleSet prev = make_set(1000, {}), cur(1000);
  for (uint32_t id = 0; id < 250; ++id) cur.insert(id);
  const SetDiff d = diff_sets(prev, cur);
  auto chunks = wire::chunk_node_diff(3, d.added, d.removed, 100);
  chunks.erase(chunks.begin() + 1);
  DiffReceiver rx;
  for (const auto& c : chunks) ASSERT_FALSE(rx.on_diff(prev, c));
  EXPECT_EQ(rx.on_end_of_frame(prev, make_end_of_frame(3, d, cur)).value_or(""),
            "desync at frame 3: received 150 added / 0 removed ids, sender's end_of_frame says "
            "250 / 0");
}

TEST(DiffReceiver, DetectsACorruptedIdThroughTheHash) {
  VisibleSet prev(1000), cur(1000);
  for (uint32_t id = 0; id < 50; ++id) cur.insert(id);
  const SetDiff d = diff_sets(prev, cur);
  auto chunk = wire::chunk_node_diff(4, d.added, d.removed, 100).at(0);
  chunk.added[10] = 999;  // same counts, different set
  DiffReceiver rx;
  ASSERT_FALSE(rx.on_diff(prev, chunk));
  const std::string err = rx.on_end_of_frame(prev, make_end_of_frame(4, d, cur)).value_or("");
  EXPECT_NE(err.find("desync at frame 4: rebuilt set has 50 ids, hash 0x"), std::string::npos)
      << err;
}

TEST(DiffReceiver, RejectsFramesOutOfOrder) {
  VisibleSet s(100);
  DiffReceiver rx;
  ASSERT_FALSE(rx.on_diff(s, wire::NodeDiff{10, {1}, {}}));
  EXPECT_EQ(rx.on_diff(s, wire::NodeDiff{11, {2}, {}}).value_or(""),
            "frame 11: node_diff while frame 10 is still open");
  EXPECT_EQ(rx.on_end_of_frame(s, wire::EndOfFrame{12}).value_or(""),
            "frame 12: end_of_frame while frame 10 is still open");
  wire::EndOfFrame eof{10, 1, 0, 1, s.hash()};
  ASSERT_FALSE(rx.on_end_of_frame(s, eof));
  EXPECT_EQ(rx.on_diff(s, wire::NodeDiff{10, {3}, {}}).value_or(""),
            "frame 10: node_diff after frame 10 (frame numbers must increase)");
  eof.frame = 9;
  EXPECT_EQ(rx.on_end_of_frame(s, eof).value_or(""),
            "frame 9: end_of_frame after frame 10 (frame numbers must increase)");
  // A frame without changes is only an EndOfFrame.
  eof.frame = 12;
  eof.total_added = 0;
  EXPECT_FALSE(rx.on_end_of_frame(s, eof));
}
