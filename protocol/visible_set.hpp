// Visible-set algebra of incremental transmission (paper 3.4), pure and in one place:
//   sender:   (added, removed) = diff_sets(V_{f-1}, V_f)   i.e. δ(f,f-1) = V_f − V_{f-1},
//                                                              δ(f-1,f) = V_{f-1} − V_f
//   receiver: V_f = (V_{f-1} − removed) ∪ added            apply(), chunk by chunk
//   both:     set_hash(V_f) in EndOfFrame; a rebuilt set that disagrees is a desync error.
// Node ids are the hierarchy's dense u32 ids, so a set is a dense membership table plus a member
// list: every operation is O(1) per id and the hash is maintained incrementally.
#pragma once
#include <cstdint>
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "common/hash.hpp"
#include "protocol/wire.hpp"

namespace occ {

// Order-independent 64-bit hash of a set of distinct ids (IdSetSums of the ids, common/hash.hpp,
// finalised with the count). Identical on every process and build.
uint64_t set_hash(std::span<const uint32_t> ids);

// A set of node ids in [0, id_limit) (id_limit = hierarchy node count). Memory: 4 bytes per
// possible id plus 4 per member.
class VisibleSet {
 public:
  explicit VisibleSet(uint32_t id_limit = 0);

  uint32_t id_limit() const { return static_cast<uint32_t>(slot_.size()); }
  size_t size() const { return ids_.size(); }
  bool empty() const { return ids_.empty(); }
  bool contains(uint32_t id) const { return id < slot_.size() && slot_[id] != 0; }
  // Return whether the set changed. insert() throws std::out_of_range for id >= id_limit.
  bool insert(uint32_t id);
  bool erase(uint32_t id);
  void clear();
  // Members in unspecified order (deterministic for a given sequence of operations).
  std::span<const uint32_t> ids() const { return ids_; }
  // Equals set_hash(ids()), in O(1).
  uint64_t hash() const;
  // Same members, order ignored.
  bool operator==(const VisibleSet& other) const;

 private:
  std::vector<uint32_t> ids_;
  std::vector<uint32_t> slot_;  // slot_[id] = 1 + position in ids_, 0 = absent
  IdSetSums sums_;
};

struct SetDiff {
  std::vector<uint32_t> added;    // in cur, not in prev (cur's order)
  std::vector<uint32_t> removed;  // in prev, not in cur (prev's order)
};

// O(|prev| + |cur|).
SetDiff diff_sets(const VisibleSet& prev, const VisibleSet& cur);

// V = (V − diff.removed) ∪ diff.added for one chunk (a chunk that passed wire::invalid_reason,
// i.e. no id listed twice). Atomic: on error `set` is unchanged and the reason names the frame
// and the id ("frame 12: removing id 7 that is not in the set", adding an id that is already in
// the set or >= id_limit).
std::optional<std::string> apply(VisibleSet& set, const wire::NodeDiff& diff);

// Checks |V_f| and the hash of a rebuilt set against the sender's EndOfFrame; the desync error
// names the frame and both values of both.
std::optional<std::string> verify(const wire::EndOfFrame& eof, const VisibleSet& set);

// Sender side: the set fields of EndOfFrame(frame) after sending `diff`, with cur = V_f. The
// statistics fields are left 0 for the caller.
wire::EndOfFrame make_end_of_frame(uint32_t frame, const SetDiff& diff, const VisibleSet& cur);

// Receiving end of one diff stream (OR or RVG): applies a frame's NodeDiff chunks and checks its
// EndOfFrame (totals, |V_f|, hash). Contract: chunks of frame f then EndOfFrame(f); frame
// numbers increase from frame to frame (gaps allowed: a switch node receives every other frame).
// Any error means the stream can no longer be trusted: end the connection.
class DiffReceiver {
 public:
  std::optional<std::string> on_diff(VisibleSet& set, const wire::NodeDiff& diff);
  std::optional<std::string> on_end_of_frame(const VisibleSet& set, const wire::EndOfFrame& eof);
  std::optional<uint32_t> last_frame() const { return last_frame_; }  // last verified frame

 private:
  std::optional<std::string> check_frame(uint32_t frame, const char* what) const;
  std::optional<uint32_t> open_frame_;  // frame whose chunks are arriving
  std::optional<uint32_t> last_frame_;
  uint64_t added_ = 0, removed_ = 0;  // totals of the open frame
};

// Sending end of one diff stream (HC, or the depth-readback server): streams V_f's new ids in
// NodeDiff chunks of at most chunk_ids as the traversal finds them, then V_{f-1}'s removed ids,
// then hands back the EndOfFrame. send() throws to abort.
class DiffSender {
 public:
  using Send = std::function<void(const wire::Message&)>;
  DiffSender(uint32_t chunk_ids, Send send);

  // Starts frame `frame` against `prev` (V_{f-1}; with front tracking the coarsened V'), which
  // must stay unchanged until end().
  void begin(uint32_t frame, const VisibleSet& prev);
  // The traversal accepted `id`: sent (in a chunk) unless prev already holds it.
  void visible(uint32_t id);
  // Flushes the added ids and sends the removed ones (prev − cur); returns EndOfFrame(frame) with
  // the set fields filled, for the caller to add its statistics and send with send().
  wire::EndOfFrame end(const VisibleSet& cur);
  void send(const wire::Message& m) { send_(m); }

 private:
  void flush(bool force);
  uint32_t chunk_ids_;
  Send send_;
  uint32_t frame_ = 0;
  const VisibleSet* prev_ = nullptr;
  SetDiff diff_;
  std::vector<uint32_t> pending_;
};

}  // namespace occ
