// The real-time loop (AMBF Eq. 1) on a fake clock: the substeps
// advance the clock by their cost, a frame adds a fixed overhead (rendering,
// I/O). Fast steps: RTF → 1 and N follows the elapsed time; slow steps: N is
// clamped at N_max, the frame is reported behind and RTF = δt / cost < 1.
#include <gtest/gtest.h>

#include "sflsh/core/error.hpp"
#include "sflsh/sim/realtime_loop.hpp"

using namespace sflsh;

namespace {

struct FakeRun {
  double rtf = 0;
  int max_n = 0, min_n = 1 << 30;
  long long behind = 0;
  double sim_minus_wall = 0;  // at the end, s
};

/// `frames` frames of a loop with substep δt, N_max, each substep costing `cost` s, each frame `overhead` s.
FakeRun run(double dt, int n_max, double cost, double overhead, int frames) {
  double now = 100.0;  // the fake clock, s
  RealtimeLoop loop({dt, n_max}, [&] { return now; });
  FakeRun r;
  double last_t = -1;
  for (int f = 0; f < frames; ++f) {
    now += overhead;
    const RealtimeFrame fr = loop.frame([&](double t) {
      EXPECT_GT(t, last_t);  // substeps see increasing simulated times
      last_t = t;
      now += cost;
    });
    if (f >= 5) r.max_n = std::max(r.max_n, fr.substeps), r.min_n = std::min(r.min_n, fr.substeps);
    EXPECT_LE(fr.substeps, n_max);
  }
  r.rtf = loop.rtf();
  r.behind = loop.frames_behind();
  r.sim_minus_wall = loop.sim_time() - (now - 100.0);
  return r;
}

TEST(RealtimeLoop, FastStepsKeepRealTime) {
  // δt = 2 ms, a substep costs 0.2 ms, a frame 16 ms: N ≈ 16.0 / (2 − 0.2) = 9 per frame.
  const FakeRun r = run(0.002, 20, 0.0002, 0.016, 500);
  EXPECT_NEAR(r.rtf, 1.0, 0.002);
  EXPECT_EQ(r.behind, 0);
  EXPECT_LT(std::abs(r.sim_minus_wall), 0.002 + 1e-12);  // within one substep of the wall clock
  EXPECT_GE(r.min_n, 8);
  EXPECT_LE(r.max_n, 10);
}

TEST(RealtimeLoop, SlowStepsClampAtNMaxAndReportRtfBelowOne) {
  // A substep costs 5 ms of wall time for 2 ms simulated: each frame runs N_max = 4.
  const int n_max = 4;
  const FakeRun r = run(0.002, n_max, 0.005, 0.001, 200);
  EXPECT_EQ(r.max_n, n_max);
  EXPECT_EQ(r.min_n, n_max);
  EXPECT_GE(r.behind, 195);
  // RTF = sim / wall = 4·2 ms / (4·5 ms + 1 ms) per frame.
  EXPECT_NEAR(r.rtf, 0.008 / 0.021, 3e-3);
  EXPECT_LT(r.rtf, 1.0);
}

TEST(RealtimeLoop, AheadOfTheClockRunsNoSubstepAndRejectsBadOptions) {
  double now = 0;
  RealtimeLoop loop({0.01, 5}, [&] { return now; });
  now = 0.025;
  EXPECT_EQ(loop.frame([](double) {}).substeps, 3);  // ⌈2.5⌉
  now = 0.027;
  EXPECT_EQ(loop.frame([](double) {}).substeps, 0);  // simulated 30 ms > 27 ms
  EXPECT_NEAR(loop.time_to_next(), 0.003, 1e-12);
  EXPECT_THROW(RealtimeLoop({0.0, 5}), Error);
  EXPECT_THROW(RealtimeLoop({0.01, 0}), Error);
}

TEST(RealtimeLoop, AStalledFrameDropsItsLagOnceAndFastFramesAfterItKeepTheClock) {
  // δt = 10 ms, N_max = 3. A 100 ms stall: the next frame runs 3 substeps and
  // drops the other 70 ms (not caught up later); frames after it run just what
  // the clock asks, counted from the dropped time.
  double now = 0;
  RealtimeLoop loop({0.01, 3}, [&] { return now; });
  now = 0.1;
  const RealtimeFrame stalled = loop.frame([](double) {});
  EXPECT_EQ(stalled.substeps, 3);
  EXPECT_TRUE(stalled.behind);
  EXPECT_NEAR(stalled.dropped, 0.07, 1e-12);  // lag 100 ms − 3 × 10 ms run
  EXPECT_NEAR(loop.dropped(), 0.07, 1e-12);
  EXPECT_NEAR(loop.time_to_next(), 0.0, 1e-12);  // sim 30 ms + dropped 70 ms = the wall clock
  now = 0.105;
  EXPECT_NEAR(loop.time_to_next(), -0.005, 1e-12);
  const RealtimeFrame next = loop.frame([](double) {});
  EXPECT_EQ(next.substeps, 1);  // 5 ms of lag since the stall: one substep, not the dropped 70 ms again
  EXPECT_FALSE(next.behind);
  EXPECT_NEAR(loop.time_to_next(), 0.005, 1e-12);  // sim 40 ms + 70 ms dropped, 5 ms ahead of 105 ms
  now = 0.12;
  EXPECT_EQ(loop.frame([](double) {}).substeps, 1);
  EXPECT_NEAR(loop.sim_time(), 0.05, 1e-12);
  EXPECT_EQ(loop.frames_behind(), 1);
}

}  // namespace
