// OcclusionGate (common/cull/occlusion_gate.hpp): the render client's choice, per camera, between the
// switch with occlusion and frustum sets, driven by simulated frame intervals. The simulated
// pipeline shows each decision `lag` frames later, as the cluster does (cameras go out ahead).
#include <gtest/gtest.h>

#include <cmath>
#include <deque>
#include <functional>

#include "common/cull/occlusion_gate.hpp"

namespace occ {
namespace {

struct Sim {
  // interval(frame, mode): what a displayed frame measures (mode: Camera.occlusion, 0 without
  // occlusion, 1 with); triangles drawn with occlusion and without (the frustum set).
  std::function<double(uint32_t, uint8_t)> interval;
  uint64_t visible_triangles = 1000, frustum_triangles = 1100;
  uint32_t lag = 2;
  uint32_t off_frames = 0;
  std::vector<bool> shown = {};  // per displayed frame: with occlusion
  std::vector<uint8_t> modes = {};
  // Whether a frame is a sample of its mode (OcclusionGate::frame's `measured`); all by default.
  std::function<bool(uint32_t, uint8_t)> measured = nullptr;
  std::vector<bool> measuring_without = {};  // per displayed frame, before it is fed
  // The frustum set's triangles of each frame (a path whose content changes; frames with
  // occlusion then draw 0.9x them: culling removes little, trials start); none: constant.
  std::function<uint64_t(uint32_t)> cost = nullptr;

  void run(OcclusionGate& g, uint32_t frames) {
    std::deque<uint8_t> in_flight;
    uint32_t camera = 0;
    for (; camera < lag; ++camera) in_flight.push_back(g.wire_occlusion(camera));
    for (uint32_t f = 0; f < frames; ++f) {
      const uint8_t mode = in_flight.front();
      in_flight.pop_front();
      in_flight.push_back(g.wire_occlusion(camera++));
      const uint64_t frustum = cost ? cost(f) : frustum_triangles;
      const uint64_t drawn = mode == 0 ? frustum : cost ? frustum * 9 / 10 : visible_triangles;
      std::optional<uint64_t> ft;
      if (mode == 0 || g.wants_frustum_triangles()) ft = frustum;
      measuring_without.push_back(g.measuring_without());
      g.frame(mode, interval(f, mode), drawn, ft, measured ? measured(f, mode) : true);
      off_frames += mode == 0;
      shown.push_back(mode != 0);
      modes.push_back(mode);
    }
  }
};

TEST(OcclusionGate, GoesWithoutOcclusionWhereItIsFasterAndStaysThere) {
  OcclusionGate g{{}};
  Sim s{[](uint32_t, bool occ) { return occ ? 18.0 : 13.0; }};
  s.run(g, 600);
  EXPECT_GE(g.trials(), 1u);
  EXPECT_GT(s.off_frames, 480u);  // the rest: the first frames and short trials with occlusion
  // It keeps checking that occlusion still does not pay: some later frames use it again.
  uint32_t late_on = 0;
  for (size_t f = 300; f < s.shown.size(); ++f) late_on += s.shown[f];
  EXPECT_GT(late_on, 0u);
  EXPECT_LT(late_on, 60u);
}

TEST(OcclusionGate, KeepsOcclusionWhereFramesWithoutItAreSlower) {
  OcclusionGate g{{}};
  Sim s{[](uint32_t, bool occ) { return occ ? 13.0 : 18.0; }};
  s.run(g, 1000);
  EXPECT_GE(g.trials(), 2u);  // it did try, and backed off
  EXPECT_LT(s.off_frames, 100u);
  EXPECT_EQ(g.state(), OcclusionGate::State::on);
}

// The first trial starts at the first frame that shows occlusion culling little, then measures
// occlusion again before it decides: a short run (a 30-frame orbit) reaches the faster
// mode early, either way round.
TEST(OcclusionGate, TheFirstTrialComesAtOnceAndMeasuresBothModesBeforeDeciding) {
  for (bool off_faster : {true, false}) {
    OcclusionGate g{{}};
    Sim s{[off_faster](uint32_t, bool occ) { return occ == off_faster ? 18.0 : 13.0; }};
    s.run(g, 40);
    size_t first_off = 0;
    while (first_off < s.shown.size() && s.shown[first_off]) ++first_off;
    EXPECT_LE(first_off, 3u) << "the first frame starts the trial; the cameras in flight show it 2 frames later";
    uint32_t on_in_trial = 0;
    for (size_t f = first_off; f < 30; ++f) on_in_trial += s.shown[f];
    EXPECT_GT(on_in_trial, 3u) << "occlusion measured again before the decision";
    EXPECT_EQ(g.state(), off_faster ? OcclusionGate::State::off : OcclusionGate::State::on) << off_faster;
    EXPECT_EQ(g.trials(), 1u);
  }
}

TEST(OcclusionGate, NeverTriesWhereOcclusionCullsMostTriangles) {
  OcclusionGate g{{}};
  // Without occlusion frames would be faster (say, a machine with spare cores), but the frustum
  // set is 3x the visible set: a trial would risk a run of heavy frames.
  Sim s{[](uint32_t, bool occ) { return occ ? 18.0 : 13.0; }, 1000, 3000};
  s.run(g, 500);
  EXPECT_EQ(g.trials(), 0u);
  EXPECT_EQ(s.off_frames, 0u);
}

// Where occlusion culls half the triangles (the frustum set 2.1x the visible set), frames
// without it are still measured, a little later: kept where faster, given up where slower.
TEST(OcclusionGate, TriesLaterWhereOcclusionCullsSomeButNotMost) {
  for (bool off_faster : {true, false}) {
    OcclusionGate g{{}};
    Sim s{[off_faster](uint32_t, bool occ) { return occ == off_faster ? 18.0 : 13.0; }, 1000, 2100};
    s.run(g, 400);
    size_t first_off = 0;
    while (first_off < s.shown.size() && s.shown[first_off]) ++first_off;
    EXPECT_GT(first_off, 8u) << "not at once";
    EXPECT_LT(first_off, 40u) << "but soon";
    EXPECT_GE(g.trials(), 1u);
    if (off_faster)
      EXPECT_GT(s.off_frames, 300u);
    else
      EXPECT_LT(s.off_frames, 80u);
  }
}

TEST(OcclusionGate, AViewWhereCullingPaysEndsFramesWithoutOcclusionAtOnce) {
  OcclusionGate g{{}};
  // Frames without occlusion are faster until frame 200, when the view turns to where culling
  // pays: without occlusion a frame takes 10x.
  Sim s{[](uint32_t f, bool occ) { return occ ? 18.0 : (f < 200 ? 13.0 : 130.0); }};
  s.run(g, 400);
  ASSERT_GT(s.off_frames, 100u);
  uint32_t slow_frames = 0;
  for (size_t f = 200; f < s.shown.size(); ++f) slow_frames += !s.shown[f];
  // Each later trial stops at its first settled frame; the back-off spaces them out.
  EXPECT_LT(slow_frames, 40u);
  uint32_t run = 0, longest = 0;
  for (size_t f = 200; f < s.shown.size(); ++f) {
    run = s.shown[f] ? 0 : run + 1;
    longest = std::max(longest, run);
  }
  EXPECT_LE(longest, 3u + 2u + 2u);  // settle, the two frames that give up, the pipeline's lag
}

TEST(OcclusionGate, OneSlowFrameDoesNotEndFramesWithoutOcclusion) {
  // Without occlusion frames are faster, but every 40th frame takes 3x (a scheduling hiccup on
  // a busy machine): the gate goes without occlusion as it does with no hiccups at all.
  auto run = [](bool hiccups) {
    OcclusionGate g{{}};
    Sim s{[hiccups](uint32_t f, bool occ) { return (hiccups && f % 40 == 39 ? 3.0 : 1.0) * (occ ? 18.0 : 13.0); }};
    s.run(g, 600);
    return s.off_frames;
  };
  const uint32_t calm = run(false), noisy = run(true);
  EXPECT_GT(calm, 480u);
  EXPECT_GT(noisy, 480u);
  EXPECT_GE(noisy + 10, calm);
  // Two slow frames in a row still end them (AViewWhereCullingPaysEndsFramesWithoutOcclusionAtOnce);
  // with give_up_frames 1 a single one does, as before.
  OcclusionGate eager{{.give_up_frames = 1}};
  Sim s{[](uint32_t f, bool occ) { return (f % 40 == 39 ? 3.0 : 1.0) * (occ ? 18.0 : 13.0); }};
  s.run(eager, 600);
  EXPECT_LT(s.off_frames, calm - 100);
}

// On a path whose cost drifts (a walk into a heavier part of the scene, or out of it), the
// frames of a trial come later than those it is compared with. Each mode is measured on both sides
// of the other's window (A B A), so the drift cancels and the mode faster on the same view wins,
// whichever way the cost drifts.
TEST(OcclusionGate, ATrialIsBracketedSoADriftingPathDoesNotDecideIt) {
  for (double slope : {1.5, -1.5})
    for (bool off_faster : {true, false}) {
      OcclusionGate g{{}};
      // A frame time rising steadily, or falling as fast: over the 11 frames between two windows
      // it drifts by more than the margin by which the faster mode beats the other on the same
      // view (0.9x).
      Sim s{[=](uint32_t f, bool occ) { return ((slope > 0 ? 100.0 : 300.0) + slope * f) * (occ == off_faster ? 1.0 : 0.9); }};
      s.run(g, 100);
      if (off_faster)
        EXPECT_GT(s.off_frames, 60u) << "slope " << slope;
      else
        EXPECT_LT(s.off_frames, 45u) << "slope " << slope;  // the trial's two windows without occlusion
    }
}

// Where occlusion makes frames clearly slower (Sponza at 512^2: the OR draws nearly the whole
// frustum set again on the same two cores), each window with it ends early, as frames without
// occlusion do the other way: at its second settled frame over give_up x the other mode's
// median, or its third over lose x. A 120-frame walk spent 29 frames with occlusion without this.
TEST(OcclusionGate, AClearlySlowerTrialOfOcclusionEndsEarly) {
  auto frames_with_occlusion = [](double occlusion_ms) {
    OcclusionGate g{{}};
    Sim s{[=](uint32_t, bool occ) { return occ ? occlusion_ms : 10.0; }};
    s.run(g, 120);
    EXPECT_FALSE(g.occlusion(120)) << occlusion_ms << " ms: frames without occlusion won";
    return 120u - s.off_frames;
  };
  const uint32_t first = 3, settle = 3, lag = 2;  // the first frames; two windows of occlusion follow
  EXPECT_LE(frames_with_occlusion(20.0), first + 2 * (settle + 2 + lag)) << "give_up x: two frames";
  EXPECT_LE(frames_with_occlusion(13.0), first + 2 * (settle + 3 + lag)) << "lose x: three frames";
  // Slower by less than lose x: both windows are measured in full.
  EXPECT_GE(frames_with_occlusion(12.0), first + 2 * (settle + 8 + lag) - 2);
}

// The --two-pass gate's start: one pass (the mode "without"), then a trial of two passes after
// a full window of one, bracketed by one pass again (A B A); kept where faster.
TEST(OcclusionGate, StartsWithoutAndTriesItAfterAFullWindow) {
  for (bool on_faster : {true, false}) {
    OcclusionGate g{{.start_on = false}};
    EXPECT_FALSE(g.occlusion(0));
    EXPECT_FALSE(g.decided_occlusion());
    Sim s{[on_faster](uint32_t, bool occ) { return occ == on_faster ? 13.0 : 18.0; }};
    s.lag = 1;  // the drawer's mode takes effect in the frame it is chosen
    s.run(g, 200);
    size_t first_on = 0;
    while (first_on < s.shown.size() && !s.shown[first_on]) ++first_on;
    EXPECT_GE(first_on, 3u + 8u) << "a full window without it first";
    EXPECT_LT(first_on, 20u);
    EXPECT_EQ(g.decided_occlusion(), on_faster);
    if (on_faster)
      EXPECT_LT(s.off_frames, 60u);
    else
      EXPECT_GT(s.off_frames, 170u);
  }
}

// A trial waits for a full window of samples without it, its baseline, so that a clear loss
// ends it early: the --two-pass gate's first frames are not samples (the occlusion gate was
// measuring), its trial comes after eight measured frames and, 1.4x slower, ends after its
// settling frames and three more instead of running a whole window.
TEST(OcclusionGate, ATrialWaitsForAFullBaselineAndEndsAtAClearLoss) {
  OcclusionGate g{{.start_on = false}};
  Sim s{[](uint32_t, bool occ) { return occ ? 14.0 : 10.0; }};
  s.lag = 1;
  s.measured = [](uint32_t f, uint8_t) { return f >= 30; };
  s.run(g, 80);
  size_t first_on = 0;
  while (first_on < s.shown.size() && !s.shown[first_on]) ++first_on;
  EXPECT_GE(first_on, 30u + 8u) << "a window of measured frames without it first";
  size_t on = 0;
  for (size_t f = first_on; f < s.shown.size() && s.shown[f]; ++f) ++on;
  EXPECT_LE(on, 3u + 3u + s.lag) << "the clear loss: settle + lose_frames (+ the lag)";
  EXPECT_FALSE(g.decided_occlusion());
}

// A path whose content falls unevenly (a full view narrowing, as on Sponza's walk): each frame
// costs a constant plus a time proportional to its frustum set's triangles, the slower mode 1.15x
// that (within lose x: every window runs in full). The bracket's means, before and after a trial,
// would make the later, lighter window look faster; judged on the frames' content, the gate
// keeps to the faster mode but for its trials, whichever mode it starts with.
TEST(OcclusionGate, ADriftingPathIsJudgedByItsFramesContent) {
  const auto triangles = [](uint32_t f) { return uint64_t(15000 + 135000 * std::exp(-double(f) / 8.0)); };
  for (bool start_on : {true, false}) {
    for (bool faster_with : {true, false}) {
      OcclusionGate g{{.start_on = start_on}};
      Sim s{[&](uint32_t f, uint8_t occ) {
        const double ms = 0.5 + double(triangles(f)) / 15000.0;
        return (occ != 0) == faster_with ? ms : 1.15 * ms;
      }};
      s.cost = triangles;
      s.lag = start_on ? 2 : 1;
      s.run(g, 120);
      uint32_t right = 0;
      for (size_t f = 60; f < s.shown.size(); ++f) right += s.shown[f] == faster_with;
      std::string m;
      for (bool b : s.shown) m += b ? '1' : '0';
      EXPECT_GE(right, 45u) << m << "\nstart_on " << start_on << ", faster with occlusion " << faster_with << ": "
                            << g.describe();
    }
  }
}

// Frames that are not samples of their mode (the render client's frustum sets while its
// --two-pass gate tries the other way) count for settling but not as measurements: frames
// without occlusion are faster, but two of every three of them, unmeasured, take 3x; the gate
// goes without occlusion as if they were not there. Measured, they keep it on occlusion.
TEST(OcclusionGate, FramesThatAreNotSamplesDoNotDecide) {
  auto off_frames = [](bool flagged) {
    OcclusionGate g{{}};
    Sim s{[](uint32_t f, bool occ) { return occ ? 18.0 : (f % 3 != 0 ? 39.0 : 13.0); }};
    if (flagged) s.measured = [](uint32_t f, uint8_t occ) { return occ != 0 || f % 3 == 0; };
    s.run(g, 400);
    return s.off_frames;
  };
  EXPECT_GT(off_frames(true), 320u);
  EXPECT_LT(off_frames(false), 200u);
}

// measuring_without(): exactly the windows that measure frames without occlusion against it.
TEST(OcclusionGate, MeasuringWithoutIsTheWindowsWithoutOcclusionOfATrial) {
  OcclusionGate g{{}};
  Sim s{[](uint32_t, bool occ) { return occ ? 14.0 : 13.0; }};  // within lose x: full windows
  s.run(g, 300);
  uint32_t measuring = 0, windows = 0, measuring_with_occlusion_shown = 0;
  for (size_t f = 0; f < s.shown.size(); ++f) {
    measuring += s.measuring_without[f];
    windows += s.measuring_without[f] && (f == 0 || !s.measuring_without[f - 1]);
    measuring_with_occlusion_shown += s.measuring_without[f] && s.shown[f];
  }
  EXPECT_GE(windows, 2u) << "a trial's window and the one after the trial with occlusion";
  EXPECT_GE(measuring, windows * 8u);
  EXPECT_LE(measuring_with_occlusion_shown, windows * s.lag) << "only the pipeline's lag at a window's start";
  EXPECT_FALSE(g.measuring_without() && g.steady());
}

TEST(OcclusionGate, FixedPoliciesIgnoreTimings) {
  for (auto [policy, expect_off] : {std::pair{OcclusionGate::Policy::on, 0u}, {OcclusionGate::Policy::off, 100u}}) {
    OcclusionGate g{{.policy = policy}};
    Sim s{[](uint32_t, bool occ) { return occ ? 18.0 : 13.0; }};
    s.run(g, 100);
    EXPECT_EQ(s.off_frames, expect_off);
    EXPECT_EQ(g.trials(), 0u);
  }
}

// Policy::alternate (--occlusion alternate:N): N cameras each way in turn, whatever the timings.
TEST(OcclusionGate, AlternateSwitchesEveryPeriodWhateverTheTimings) {
  for (uint32_t every_n : {1u, 4u}) {
    OcclusionGate every{{.policy = OcclusionGate::Policy::alternate, .alternate_every = every_n}};
    Sim s{[](uint32_t, bool occ) { return occ ? 18.0 : 13.0; }};
    s.run(every, 16);
    for (uint32_t c = 0; c < 16; ++c) EXPECT_EQ(every.occlusion(c), (c / every_n) % 2 == 0) << c;
    EXPECT_EQ(s.off_frames, 8u);
    EXPECT_FALSE(every.wants_frustum_triangles());
    EXPECT_EQ(every.trials(), 0u);
  }
}

}  // namespace
}  // namespace occ
