// Occlusion only where it pays, for the cluster as a whole: the render client decides
// for every camera it sends whether the switch culls that frame with occlusion (the OR draws the
// previous visible set, HC queries: the switch as designed) or without (the HC node sends the
// frustum set at the chosen LODs: no OR, no queries; wire.hpp Camera.occlusion). It decides from
// the figure the user sees, the frame interval at the display, so the choice fits any placement
// of the three processes (one machine with two cores, three machines) without a model of it:
//   - frames start with occlusion;
//   - while occlusion culls little (the frustum set's triangles are fewer than try_below x the
//     visible set's, checked from the first frame on; or fewer than try_eventually_below x, after
//     `deferrals` such checks), a trial runs frames without it (the render
//     client then culls the frustum sets itself where that pays: TwoPassDrawer,
//     common/gl/two_pass.hpp); after `settle` frames (the pipeline's change of mode) `window`
//     frames are measured; then the first mode is measured again (`settle` + `window` frames),
//     and the trial's median is compared, by `margin`, with the mean of the other mode's medians
//     before and after it (A B A: on a camera path whose cost drifts, the two windows of A
//     bracket B's, so a walk getting heavier does not make the later mode look slower); a
//     failed trial doubles the wait before the next (first_hold .. max_hold); any of these
//     windows ends early at a clear loss: give_up_frames settled frames in a row over give_up x
//     the other mode's median, or lose_frames over lose x (a window of the clearly slower mode
//     costs settle + a few frames, not settle + window; where the path's own cost drifts by as
//     much, the windows still run in full and the bracket decides);
//   - frames without occlusion run for `hold` frames (doubling while they keep winning), then
//     occlusion is tried again the same way (B A B; a first trial that came before a full window
//     of occlusion, B A B too); give_up_frames frames in a row without it that take give_up x
//     the median (the view changed: culling may pay now) end them at once, and then the window
//     with occlusion after them decides alone. One slow frame does not: on two cores a
//     scheduling hiccup doubles a frame now and then, and one such frame must not send the rest
//     of a run back to occlusion.
// A trial is decided on the frames' own content, not only on their time: where both modes' frames
// carry the frustum set's triangles T (frames with occlusion: those of the trial's windows, and of
// the window before it where a trial could start), the frames without occlusion of the trial and
// the windows around it are fitted as ms = a + b T (Theil-Sen: b the median of the pairwise
// slopes, at least 0), and the median with occlusion is compared with that fit's median at the
// same frames' T.
// So a path whose cost falls or rises unevenly (a walk from a full view into a narrow one)
// does not make the later window look faster; the bracket's means decide only where T is not
// known or does not vary.
// The render client's choice between two passes and one for those frustum sets (--occlusion) is a
// second gate of this kind, fed the render time: "occlusion" there means two passes.
// Either way is conservative: the frustum set holds the visible set, so frames never change.
// GL-free and clock-free: the caller feeds it what each displayed frame measured.
#pragma once
#include <cstdint>
#include <deque>
#include <optional>
#include <string>
#include <vector>

namespace occ {

class OcclusionGate {
 public:
  // automatic (above); on: always occlusion (the switch as designed); off: frustum sets only;
  // alternate: `alternate_every` cameras each way in turn, starting with occlusion (every method
  // on one path, and both changes of mode many times).
  enum class Policy { automatic, on, off, alternate };
  struct Options {
    Policy policy = Policy::automatic;
    uint32_t alternate_every = 4;  // Policy::alternate: at least 1
    uint32_t window = 8, settle = 3;
    // A trial needs this many settled frames with occlusion measured (at most `window`). With
    // fewer than `window` of them it ends by measuring occlusion again (a trial with it) before
    // deciding; 0: the first frame may start one (a short run, e.g. a 30-frame orbit, would
    // otherwise spend a third of it waiting).
    uint32_t trial_after = 0;
    double try_below = 1.6;
    // Below this ratio (but not under try_below) a trial still comes after `deferrals` checks
    // found culling paying: it must be measured, not assumed (a frustum set twice the visible
    // set can still give faster frames on two cores). At or above it a trial would risk a run of
    // heavy frames.
    double try_eventually_below = 2.5;
    uint32_t deferrals = 2;
    double margin = 0.95;
    uint32_t first_hold = 32, max_hold = 1024;
    double give_up = 1.5;
    uint32_t give_up_frames = 2;
    // A window measuring one mode against the other (a trial, or the mode before it measured
    // again) also ends at lose_frames in a row over lose x the other's median: a clear loss.
    double lose = 1.25;
    uint32_t lose_frames = 3;
    // false: frames start without occlusion, and the first trial of it comes after a full
    // window without it (A B A; the two-pass gate: one pass is the baseline that frames of
    // frustum sets are measured in, below).
    bool start_on = true;
  };
  explicit OcclusionGate(const Options& o);

  // Whether the next camera sent (number `camera`) is culled with occlusion.
  bool occlusion(uint32_t camera) const;
  // Camera.occlusion for the next camera sent: 0 (the frustum set) or 1.
  uint8_t wire_occlusion(uint32_t camera) const { return occlusion(camera) ? 1 : 0; }
  // Whether frame() of a frame with occlusion should carry the frustum set's triangles (a frustum
  // cull on the render client, which costs time on big scenes, so computed only when asked: while
  // a trial may start, and during a trial's windows).
  bool wants_frustum_triangles() const;
  // A frame was displayed: whether its camera had occlusion, the interval since the previous
  // frame, the triangles drawn, and the frustum set's triangles: for a frame with occlusion when
  // asked, for a frame without it always (the set's, also where the frame drew fewer; without
  // it, the drawn triangles stand in). They start trials (how much occlusion culls) and are each
  // frame's cost measure (below).
  // `measured` false: the frame counts (modes, settling) but its interval is not a sample of
  // its mode (the render client's frustum sets drawn while its two-pass gate tried the other
  // way: not what frames without occlusion cost).
  void frame(bool occlusion, double interval_ms, uint64_t drawn_triangles,
             std::optional<uint64_t> frustum_triangles = std::nullopt, bool measured = true);
  // Whether a window is measuring frames without occlusion against occlusion (a trial without
  // it, or frames without it measured again after a trial with it): the render client's
  // two-pass gate holds still meanwhile, one experiment at a time.
  bool measuring_without() const;
  // Whether no trial is in progress (on or off, as last decided).
  bool steady() const { return state_ == State::on || state_ == State::off; }
  // The mode of the last decision, that a trial in progress is measured against.
  bool decided_occlusion() const;

  // For logs and tests.
  // confirm_on / confirm_off: after a trial, the mode before it measured again (A B A).
  enum class State { on, trial_off, off, trial_on, confirm_on, confirm_off };
  State state() const { return state_; }
  uint32_t trials() const { return trials_; }           // trials of frames without occlusion
  uint32_t frames_off() const { return frames_off_; }   // displayed frames without occlusion
  // `mode`: what "on" means to the caller ("occlusion", "two passes").
  std::string describe(const std::string& mode = "occlusion") const;

 private:
  // A settled sample of a trial's windows (the window before it included).
  struct Sample {
    bool occlusion = false;
    double ms = 0;
    uint64_t cost = 0;  // the frustum set's triangles (0: not known)
  };
  // The median with occlusion of the trial's samples and the fit of those without it at the
  // same frames (above); nullopt where the samples do not allow the fit.
  struct Compared {
    double with = 0, without = 0;
  };
  std::optional<Compared> compare() const;
  bool may_try() const;  // a trial of frames without occlusion may start at this frame
  static double median(const std::deque<double>& v);
  void push(std::deque<double>& ring, double v) const;
  void enter(State s);
  uint32_t doubled(uint32_t v) const;  // twice v (first_hold when 0), at most max_hold
  void back_off();                     // a trial without occlusion lost: occlusion, next trial later
  void go_off(uint32_t hold);          // frames without occlusion for `hold` frames
  void keep_on();                      // occlusion pays: occlusion, the next trial after first_hold
  bool state_occlusion() const;        // whether state_ asks for occlusion (the automatic policy)
  // The trial's median against the other mode's: the mean of its medians before and after the
  // trial (after only when the trial started before it had a full window).
  double bracket(double after) const { return before_ > 0 ? 0.5 * (before_ + after) : after; }

  Options o_;
  State state_ = State::on;
  uint32_t n_ = 0;             // frames displayed
  uint32_t same_ = 0;          // consecutive displayed frames with this frame's mode
  bool last_mode_ = true;
  std::deque<double> on_, off_;  // settled intervals of each mode, the newest `window`
  std::deque<Sample> recent_;          // the newest `window` settled samples, either mode
  std::vector<Sample> trial_samples_;  // since the trial began, and the window before it
  uint32_t fresh_ = 0;           // samples of the measured mode since the state began
  uint32_t slow_ = 0;            // consecutive settled frames over give_up x the reference median
  uint32_t lagging_ = 0;         // consecutive settled frames over lose x it (a trial's windows)
  uint32_t next_trial_ = 0;      // frame count before which no trial starts
  uint32_t deferred_ = 0;        // checks since the last trial that found try_below <= ratio < try_eventually_below
  uint32_t off_until_ = 0;       // state off: its end
  uint32_t on_wait_ = 0, off_hold_ = 0;  // current back-off of failed trials / hold of won ones
  uint32_t trials_ = 0, frames_off_ = 0;
  double before_ = 0;   // a trial's end: the other mode's median before it (0: not a full window)
  double trial_ = 0;    // a trial's median, while the mode before it is measured again
  bool confirm_ = true; // whether the trial's end measures the mode before it again
};

}  // namespace occ
