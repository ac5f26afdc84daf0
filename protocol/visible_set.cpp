#include "protocol/visible_set.hpp"

#include <bit>
#include <stdexcept>

#include "common/hash.hpp"

namespace occ {
namespace {

uint64_t finish(const IdSetSums& s, uint64_t count) {
  return mix64(s.sum ^ std::rotl(s.x, 29) ^ (count * 0xd6e8feb86659fd93ULL));
}
std::string frame_prefix(uint32_t frame) { return "frame " + std::to_string(frame) + ": "; }

}  // namespace

uint64_t set_hash(std::span<const uint32_t> ids) {
  IdSetSums s;
  for (uint32_t id : ids) s.add(id);
  return finish(s, ids.size());
}

VisibleSet::VisibleSet(uint32_t id_limit) : slot_(id_limit, 0) {}

bool VisibleSet::insert(uint32_t id) {
  if (id >= slot_.size())
    throw std::out_of_range("VisibleSet::insert: id " + std::to_string(id) + " >= id limit " +
                            std::to_string(slot_.size()));
  if (slot_[id] != 0) return false;
  ids_.push_back(id);
  slot_[id] = static_cast<uint32_t>(ids_.size());
  sums_.add(id);
  return true;
}

bool VisibleSet::erase(uint32_t id) {
  if (!contains(id)) return false;
  const uint32_t pos = slot_[id] - 1;
  const uint32_t last = ids_.back();
  ids_[pos] = last;
  slot_[last] = pos + 1;
  ids_.pop_back();
  slot_[id] = 0;
  sums_.remove(id);
  return true;
}

void VisibleSet::clear() {
  for (uint32_t id : ids_) slot_[id] = 0;
  ids_.clear();
  sums_ = {};
}

uint64_t VisibleSet::hash() const { return finish(sums_, ids_.size()); }

bool VisibleSet::operator==(const VisibleSet& other) const {
  if (size() != other.size()) return false;
  for (uint32_t id : ids_)
    if (!other.contains(id)) return false;
  return true;
}

SetDiff diff_sets(const VisibleSet& prev, const VisibleSet& cur) {
  SetDiff d;
  for (uint32_t id : cur.ids())
    if (!prev.contains(id)) d.added.push_back(id);
  for (uint32_t id : prev.ids())
    if (!cur.contains(id)) d.removed.push_back(id);
  return d;
}

std::optional<std::string> apply(VisibleSet& set, const wire::NodeDiff& diff) {
  // Mutate, and undo the applied prefix on the first bad id.
  size_t removed = 0, added = 0;
  auto undo = [&] {
    for (size_t i = 0; i < added; ++i) set.erase(diff.added[i]);
    for (size_t i = 0; i < removed; ++i) set.insert(diff.removed[i]);
  };
  for (; removed < diff.removed.size(); ++removed) {
    const uint32_t id = diff.removed[removed];
    if (!set.erase(id)) {
      undo();
      return frame_prefix(diff.frame) + "removing id " + std::to_string(id) +
             " that is not in the set";
    }
  }
  for (; added < diff.added.size(); ++added) {
    const uint32_t id = diff.added[added];
    if (id >= set.id_limit() || set.contains(id)) {
      undo();
      return frame_prefix(diff.frame) + "adding id " + std::to_string(id) +
             (id >= set.id_limit()
                  ? " out of range (" + std::to_string(set.id_limit()) + " nodes)"
                  : std::string(" that is already in the set"));
    }
    set.insert(id);
  }
  return std::nullopt;
}

std::optional<std::string> verify(const wire::EndOfFrame& eof, const VisibleSet& set) {
  if (eof.visible_count == set.size() && eof.set_hash == set.hash()) return std::nullopt;
  return "desync at frame " + std::to_string(eof.frame) + ": rebuilt set has " +
         std::to_string(set.size()) + " ids, hash " + hex(set.hash()) + "; sender's end_of_frame " +
         "says " + std::to_string(eof.visible_count) + " ids, hash " + hex(eof.set_hash);
}

wire::EndOfFrame make_end_of_frame(uint32_t frame, const SetDiff& diff, const VisibleSet& cur) {
  wire::EndOfFrame eof;
  eof.frame = frame;
  eof.total_added = static_cast<uint32_t>(diff.added.size());
  eof.total_removed = static_cast<uint32_t>(diff.removed.size());
  eof.visible_count = static_cast<uint32_t>(cur.size());
  eof.set_hash = cur.hash();
  return eof;
}

std::optional<std::string> DiffReceiver::check_frame(uint32_t frame, const char* what) const {
  if (open_frame_ && frame != *open_frame_)
    return frame_prefix(frame) + what + " while frame " + std::to_string(*open_frame_) +
           " is still open";
  if (!open_frame_ && last_frame_ && frame <= *last_frame_)
    return frame_prefix(frame) + what + " after frame " + std::to_string(*last_frame_) +
           " (frame numbers must increase)";
  return std::nullopt;
}

std::optional<std::string> DiffReceiver::on_diff(VisibleSet& set, const wire::NodeDiff& diff) {
  if (auto e = check_frame(diff.frame, "node_diff")) return e;
  if (auto e = apply(set, diff)) return e;
  open_frame_ = diff.frame;
  added_ += diff.added.size();
  removed_ += diff.removed.size();
  return std::nullopt;
}

std::optional<std::string> DiffReceiver::on_end_of_frame(const VisibleSet& set,
                                                         const wire::EndOfFrame& eof) {
  if (auto e = check_frame(eof.frame, "end_of_frame")) return e;
  const uint64_t added = added_, removed = removed_;
  open_frame_.reset();
  last_frame_ = eof.frame;
  added_ = removed_ = 0;
  if (added != eof.total_added || removed != eof.total_removed)
    return "desync at frame " + std::to_string(eof.frame) + ": received " +
           std::to_string(added) + " added / " + std::to_string(removed) +
           " removed ids, sender's end_of_frame says " + std::to_string(eof.total_added) + " / " +
           std::to_string(eof.total_removed);
  return verify(eof, set);
}

DiffSender::DiffSender(uint32_t chunk_ids, Send send) : chunk_ids_(chunk_ids), send_(std::move(send)) {
  if (chunk_ids_ < 1 || chunk_ids_ > wire::kMaxDiffIds)
    throw std::invalid_argument("diff chunk of " + std::to_string(chunk_ids) + " ids: must be 1.." +
                                std::to_string(wire::kMaxDiffIds));
}

void DiffSender::begin(uint32_t frame, const VisibleSet& prev) {
  frame_ = frame;
  prev_ = &prev;
  diff_ = {};
  pending_.clear();
}

void DiffSender::flush(bool force) {
  if (pending_.empty() || (!force && pending_.size() < chunk_ids_)) return;
  send_(wire::NodeDiff{frame_, pending_, {}});
  pending_.clear();
}

void DiffSender::visible(uint32_t id) {
  if (prev_->contains(id)) return;
  pending_.push_back(id);
  diff_.added.push_back(id);
  flush(false);
}

wire::EndOfFrame DiffSender::end(const VisibleSet& cur) {
  flush(true);
  for (uint32_t id : prev_->ids())
    if (!cur.contains(id)) diff_.removed.push_back(id);
  for (auto& chunk : wire::chunk_node_diff(frame_, {}, diff_.removed, chunk_ids_)) send_(chunk);
  return make_end_of_frame(frame_, diff_, cur);
}

}  // namespace occ
