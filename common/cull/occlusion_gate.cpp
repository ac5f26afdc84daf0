#include "common/cull/occlusion_gate.hpp"

#include <algorithm>
#include <sstream>
#include <vector>

namespace occ {

OcclusionGate::OcclusionGate(const Options& o) : o_(o) {
  if (o_.start_on) return;
  state_ = State::off;
  last_mode_ = false;
  off_until_ = o_.settle + o_.window + 1;  // a full window before the first trial: A B A
}

bool OcclusionGate::measuring_without() const {
  return o_.policy == Policy::automatic &&
         (state_ == State::trial_off || state_ == State::confirm_off);
}

bool OcclusionGate::decided_occlusion() const {
  if (o_.policy != Policy::automatic) return occlusion(0);
  return state_ == State::on || state_ == State::trial_off || state_ == State::confirm_on;
}

bool OcclusionGate::occlusion(uint32_t camera) const {
  switch (o_.policy) {
    case Policy::on: return true;
    case Policy::off: return false;
    case Policy::alternate: return (camera / std::max(o_.alternate_every, 1u)) % 2 == 0;
    case Policy::automatic: break;
  }
  return state_occlusion();
}

bool OcclusionGate::state_occlusion() const {
  return state_ == State::on || state_ == State::trial_on || state_ == State::confirm_on;
}

bool OcclusionGate::wants_frustum_triangles() const {
  return may_try() || (o_.policy == Policy::automatic && !steady());
}

bool OcclusionGate::may_try() const {
  return o_.policy == Policy::automatic && state_ == State::on && n_ >= next_trial_ &&
         on_.size() >= std::min(o_.trial_after, o_.window);
}

namespace {

double median_of(std::vector<double> v) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  return v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]);
}

}  // namespace

std::optional<OcclusionGate::Compared> OcclusionGate::compare() const {
  std::vector<Sample> with, without;
  for (const Sample& s : trial_samples_)
    if (s.cost > 0) (s.occlusion ? with : without).push_back(s);
  if (with.size() < 3 || without.size() < 3) return std::nullopt;
  // Slopes only between frames whose T differ by more than 0.05 of the larger: T that barely
  // varies says nothing of b.
  std::vector<double> slopes;
  for (size_t i = 0; i < without.size(); ++i)
    for (size_t j = i + 1; j < without.size(); ++j) {
      const double dx = double(without[j].cost) - double(without[i].cost);
      if (std::abs(dx) > 0.05 * double(std::max(without[i].cost, without[j].cost)))
        slopes.push_back((without[j].ms - without[i].ms) / dx);
    }
  const double b = slopes.size() >= 3 ? std::max(0.0, median_of(slopes)) : 0.0;
  std::vector<double> rest, fitted, actual;
  for (const Sample& s : without) rest.push_back(s.ms - b * double(s.cost));
  const double a = median_of(rest);
  for (const Sample& s : with) {
    fitted.push_back(std::max(0.0, a + b * double(s.cost)));
    actual.push_back(s.ms);
  }
  return Compared{median_of(actual), median_of(fitted)};
}

double OcclusionGate::median(const std::deque<double>& v) { return median_of({v.begin(), v.end()}); }

void OcclusionGate::push(std::deque<double>& ring, double v) const {
  ring.push_back(v);
  while (ring.size() > o_.window) ring.pop_front();
}

void OcclusionGate::enter(State s) {
  if (s == State::trial_off || s == State::trial_on) {  // a new experiment, from the window before it
    trial_samples_.clear();
    for (const Sample& x : recent_)
      if (x.occlusion == state_occlusion()) trial_samples_.push_back(x);
  }
  state_ = s;
  fresh_ = 0;
  slow_ = 0;
  lagging_ = 0;
  trials_ += s == State::trial_off;
  if (!steady()) (state_occlusion() ? on_ : off_).clear();  // what a trial's window measures, afresh
}

uint32_t OcclusionGate::doubled(uint32_t v) const { return std::min(2 * (v ? v : o_.first_hold), o_.max_hold); }

void OcclusionGate::back_off() {
  on_wait_ = doubled(on_wait_);
  next_trial_ = n_ + on_wait_;
  enter(State::on);
}

void OcclusionGate::keep_on() {
  off_hold_ = 0;
  on_wait_ = 0;
  next_trial_ = n_ + o_.first_hold;
  enter(State::on);
}

void OcclusionGate::go_off(uint32_t hold) {
  off_hold_ = hold;
  off_until_ = n_ + hold;
  enter(State::off);
}

void OcclusionGate::frame(bool occlusion, double interval_ms, uint64_t drawn_triangles,
                          std::optional<uint64_t> frustum_triangles, bool measured) {
  ++n_;
  same_ = occlusion == last_mode_ ? same_ + 1 : 1;
  last_mode_ = occlusion;
  if (!occlusion) ++frames_off_;
  if (o_.policy != Policy::automatic) return;
  // Only settled frames are measured: the first frames of a mode still carry the other's work
  // (the OR of the first frame with occlusion draws a whole frustum set).
  const bool settled = same_ > o_.settle && measured;
  if (settled) {
    push(occlusion ? on_ : off_, interval_ms);
    if (occlusion == state_occlusion()) ++fresh_;
    const Sample x{occlusion, interval_ms, frustum_triangles.value_or(occlusion ? 0 : drawn_triangles)};
    recent_.push_back(x);
    while (recent_.size() > o_.window) recent_.pop_front();
    if (!steady()) trial_samples_.push_back(x);
  }
  if (measured && occlusion && frustum_triangles && may_try()) {
    const double ratio = double(*frustum_triangles) / double(std::max<uint64_t>(drawn_triangles, 1));
    if (ratio < o_.try_below || (ratio < o_.try_eventually_below && deferred_ >= o_.deferrals)) {
      deferred_ = 0;
      enter(State::trial_off);
    } else {  // culling pays on this view: look again later (much later where it pays much)
      deferred_ += ratio < o_.try_eventually_below;
      next_trial_ = n_ + o_.window * (ratio > 2 * o_.try_below ? 4 : 1);
    }
  }
  if (!settled) return;
  const double med_on = median(on_), med_off = median(off_);
  // Frames without occlusion much slower than the reference median, give_up_frames in a row.
  auto gave_up = [&](double reference_ms) {
    slow_ = interval_ms > o_.give_up * reference_ms ? slow_ + 1 : 0;
    return slow_ >= std::max(o_.give_up_frames, 1u);
  };
  // A window that is measuring one mode against the other's median: it also ends once
  // lose_frames in a row take lose x that median (a clear loss needs no full window).
  auto lost = [&](double reference_ms) {
    lagging_ = interval_ms > o_.lose * reference_ms ? lagging_ + 1 : 0;
    const bool slow = gave_up(reference_ms);
    return slow || lagging_ >= std::max(o_.lose_frames, 1u);
  };
  if (state_ == State::trial_off && !occlusion) {
    // Much slower than with occlusion before it stops the trial at once; a full window is then
    // bracketed by occlusion measured again.
    const bool full_before = on_.size() >= o_.window;
    if (full_before && lost(med_on)) {
      back_off();
    } else if (fresh_ >= o_.window) {
      trial_ = med_off;
      before_ = full_before ? med_on : 0;
      enter(State::confirm_on);
    }
  } else if (state_ == State::confirm_on && occlusion && lost(trial_)) {
    go_off(off_hold_ ? off_hold_ : o_.first_hold);  // occlusion lost clearly: no full window needed
  } else if (state_ == State::confirm_on && occlusion && fresh_ >= o_.window) {
    if (before_ == 0) {  // an early trial (no full window with occlusion before it): B A, then B again
      before_ = trial_;
      trial_ = med_on;
      enter(State::confirm_off);
    } else if (const std::optional<Compared> c = compare(); c ? c->without < o_.margin * c->with
                                                               : trial_ < o_.margin * bracket(med_on))
      go_off(off_hold_ ? off_hold_ : o_.first_hold);
    else
      back_off();
  } else if (state_ == State::off && !occlusion) {
    // A trial waits for a full window of fresh samples without occlusion, its baseline (frames
    // that were not samples count for the hold but measure nothing: the two-pass gate's while
    // the occlusion gate measured): against it a clear loss ends the trial early.
    const bool slow = gave_up(med_off);
    if (slow || (n_ >= off_until_ && fresh_ >= o_.window)) {
      confirm_ = !slow;  // the view changed: frames without occlusion are not measured again
      enter(State::trial_on);
    }
  } else if (state_ == State::trial_on && occlusion && confirm_ && off_.size() >= o_.window && lost(med_off)) {
    go_off(doubled(off_hold_));  // occlusion lost clearly: no full window needed
  } else if (state_ == State::trial_on && occlusion && fresh_ >= o_.window) {
    if (!confirm_) {  // the view changed under frames without occlusion: this window decides
      if (med_on < o_.margin * med_off)
        keep_on();
      else
        go_off(doubled(off_hold_));
    } else {
      trial_ = med_on;
      before_ = off_.size() >= o_.window ? med_off : 0;
      enter(State::confirm_off);
    }
  } else if (state_ == State::confirm_off && !occlusion) {
    if (lost(trial_)) {
      keep_on();
    } else if (fresh_ >= o_.window) {
      if (const std::optional<Compared> c = compare(); c ? c->with < o_.margin * c->without
                                                         : trial_ < o_.margin * bracket(med_off))
        keep_on();
      else
        go_off(doubled(off_hold_));
    }
  }
}

std::string OcclusionGate::describe(const std::string& mode) const {
  std::ostringstream s;
  const std::string state[] = {"on", "trial without " + mode, "off", "trial with " + mode,
                               "measuring with " + mode + " after a trial", "measuring without " + mode + " after a trial"};
  const auto ms = [](const std::deque<double>& ring) {
    return ring.empty() ? std::string("not measured") : std::to_string(median(ring)) + " ms";
  };
  s << state[int(state_)] << ", " << trials_ << " trials without " << mode << ", " << frames_off_
    << " frames without; median with " << mode << " " << ms(on_) << ", without " << ms(off_);
  return s.str();
}

}  // namespace occ
