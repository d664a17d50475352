// The checks of `sflsh stress` and `sflsh stress-suite` on crafted runs (no
// simulation): judge_stress and the suite's case limits must fail a run that
// grows, rejects or damps too much, or (scenes) penetrates too deep. The
// growth of a short run (every CMU case: 11–60 steps, less than two 100-step
// windows) was compared with itself before (one window: always passed): now
// its last tenth of the steps is compared with every step before it; the
// rejected and damped counts and the scenes' contact were not checked at all.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

#include "sflsh/bench/stress_run.hpp"
#include "sflsh/bench/stress_suite.hpp"
#include "sflsh/core/error.hpp"

using namespace sflsh;

namespace {

/// A finished run whose steps had these peak soft displacements (mm), windows of `window` steps,
/// det F 0.8 everywhere, every step planned and accepted.
StressReport crafted_run(const std::vector<double>& peaks, int window) {
  StressReport r;
  r.steps = r.planned_steps = long(peaks.size());
  r.accepted = int(peaks.size());
  r.step_peak_soft_mm = peaks;
  StressWindow w;
  w.min_det = 0.8;
  for (size_t i = 0; i < peaks.size(); ++i) {
    w.peak_soft_mm = std::max(w.peak_soft_mm, peaks[i]);
    if ((i + 1) % size_t(window) == 0 || i + 1 == peaks.size()) {
      w.t_end = double(i + 1) / 30.0;
      r.windows.push_back(w);
      w = StressWindow();
      w.min_det = 0.8;
    }
  }
  return r;
}

StressOptions options(int window = 100) {
  StressOptions o;
  o.window = window;
  return o;
}

/// A CMU-like clip of n steps starting from rest: the flesh swings up to ~40 mm and settles near 30 mm.
std::vector<double> settling_clip(int n) {
  std::vector<double> p;
  for (int i = 0; i < n; ++i) p.push_back(i < 5 ? 8.0 * i : 30.0 + 10.0 * std::sin(0.7 * i));
  return p;
}

TEST(StressChecks, ShortRunThatGrowsFails) {
  // 30 steps (less than two windows of 100, like cmu_2x@1/30/16_27): settles, then the last 3 steps blow up.
  std::vector<double> p = settling_clip(30);
  p[27] = 70, p[28] = 110, p[29] = 160;  // last tenth 160 mm, 4x every step before (≤ 40 mm)
  StressReport r = crafted_run(p, 100);
  judge_stress(r, options());
  EXPECT_TRUE(r.short_run);
  EXPECT_NEAR(r.peak_soft_mm_late, 160, 1e-12);
  EXPECT_NEAR(r.peak_soft_mm_early, 40, 0.1);  // 30 + 10 sin(0.7 i), largest near i = 20
  EXPECT_FALSE(r.stable);
  EXPECT_FALSE(r.passed());
  EXPECT_NE(r.failure().find("soft displacement grew (last tenth of the steps 160.0 mm"), std::string::npos)
      << r.failure();
  // The same run read as one window (the check before) compared 160 with itself.
  EXPECT_EQ(r.windows.size(), 1u);
}

TEST(StressChecks, ShortRunFromRestThatSettlesPasses) {
  for (int n : {11, 17, 42, 60}) {
    StressReport r = crafted_run(settling_clip(n), 100);
    judge_stress(r, options());
    EXPECT_TRUE(r.short_run) << n;
    EXPECT_TRUE(r.stable) << n << ": " << r.peak_soft_mm_late << " vs " << r.peak_soft_mm_early;
    EXPECT_TRUE(r.passed()) << n << ": " << r.failure();
    EXPECT_EQ(r.failure(), "");
  }
  // cmu_3x@1/30/09_03 on the default avatar: 11 steps, the last at 69.6 mm, 1.84x every step before: the
  // clip's most violent motion, not growth (the same clip at 2x ends at 37.8 mm).
  StressReport clip = crafted_run({0, 8, 16, 24, 30, 33, 36, 37.9, 35, 33, 69.6}, 100);
  judge_stress(clip, options());
  EXPECT_TRUE(clip.passed()) << clip.failure();
  // The limit itself (short_run_growth_limit = 3): 11 steps, the last at exactly 3x the largest before
  // passes, just above fails.
  std::vector<double> p(11, 20.0);
  p.back() = 60.0;
  StressReport r = crafted_run(p, 100);
  judge_stress(r, options());
  EXPECT_TRUE(r.stable);
  r.step_peak_soft_mm.back() = 60.001;
  judge_stress(r, options());
  EXPECT_FALSE(r.stable);
  EXPECT_NE(r.failure().find("every step before 20.0 mm; at most 3.0x)"), std::string::npos) << r.failure();
}

TEST(StressChecks, LongRunComparesTheLastWindowWithTheFirstTenth) {
  // 2,000 steps in windows of 100: a steady 20 mm, then the last window at 35 mm (> 1.5 x 20).
  std::vector<double> p(2000, 20.0);
  StressReport ok = crafted_run(p, 100);
  judge_stress(ok, options());
  EXPECT_FALSE(ok.short_run);
  EXPECT_TRUE(ok.passed()) << ok.failure();
  for (int i = 1900; i < 2000; ++i) p[size_t(i)] = 35.0;
  StressReport grown = crafted_run(p, 100);
  judge_stress(grown, options());
  EXPECT_FALSE(grown.stable);
  EXPECT_NE(grown.failure().find("last window 35.0 mm, first windows 20.0 mm"), std::string::npos) << grown.failure();
  // A scene's reference is its first half (growth_reference_share 0.5): a body that tips over at 40 % of the
  // run and then lies still (20 -> 33 mm, like fall_on_floor) passes; with the first 10 % it would not.
  p.assign(2000, 20.0);
  for (int i = 800; i < 2000; ++i) p[size_t(i)] = 33.0;
  StressReport tipped = crafted_run(p, 100);
  StressOptions scene = options();
  scene.growth_reference_share = 0.5;
  judge_stress(tipped, scene);
  EXPECT_TRUE(tipped.stable) << tipped.failure();
  judge_stress(tipped, options());
  EXPECT_FALSE(tipped.stable);
  // A NaN peak fails instead of passing every comparison.
  p.assign(2000, 20.0);
  p.back() = std::numeric_limits<double>::quiet_NaN();
  StressReport nan = crafted_run(p, 100);
  nan.windows.back().peak_soft_mm = p.back();
  judge_stress(nan, options());
  EXPECT_FALSE(nan.stable);
}

TEST(StressChecks, RejectedAndDampedStepsCountAgainstTheirLimits) {
  StressReport r = crafted_run(std::vector<double>(400, 20.0), 100);
  r.rejected = 1;
  judge_stress(r, options());
  EXPECT_FALSE(r.few_rejected);
  EXPECT_FALSE(r.passed());
  EXPECT_EQ(r.failure(), "1 rejected steps (at most 0)");

  r.rejected = 0;
  r.damped = 401;  // 1.0025 per step > 1
  judge_stress(r, options());
  EXPECT_TRUE(r.few_rejected);
  EXPECT_FALSE(r.few_damped);
  EXPECT_NE(r.failure().find("401 damped Newton iterations in 400 steps (1.00 per step, at most 1.00)"),
            std::string::npos)
      << r.failure();
  r.damped = 400;
  judge_stress(r, options());
  EXPECT_TRUE(r.passed()) << r.failure();

  StressOptions strict = options();
  strict.max_damped_per_step = 0.01;  // shake's limit
  r.damped = 5;
  judge_stress(r, strict);
  EXPECT_FALSE(r.few_damped);  // 5 > 0.01 x 400
  r.damped = 4;
  judge_stress(r, strict);
  EXPECT_TRUE(r.few_damped);
}

TEST(StressChecks, InvertedIncompleteAndOffTrackRunsFail) {
  StressReport r = crafted_run(std::vector<double>(300, 20.0), 100);
  r.windows[1].min_det = -0.01;
  judge_stress(r, options());
  EXPECT_FALSE(r.no_inversion);
  EXPECT_EQ(r.failure(), "inverted cubature sample");
  r = crafted_run(std::vector<double>(300, 20.0), 100);
  r.planned_steps = 301;
  judge_stress(r, options());
  EXPECT_EQ(r.failure(), "ended after 300 of 301 steps");
  r = crafted_run(std::vector<double>(300, 20.0), 100);
  r.pelvis_error_max_mm = 21;
  judge_stress(r, options());
  EXPECT_FALSE(r.tracking);
  EXPECT_NE(r.failure().find("pelvis 21.0 mm from the motion's root (> 20.0 mm)"), std::string::npos) << r.failure();
}

TEST(StressChecks, SuiteCasesCarryTheirStatedLimits) {
  EXPECT_EQ(stress_case_limits("shake").max_damped_per_step, 0.01);
  EXPECT_EQ(stress_case_limits("torture").max_damped_per_step, 2.0);
  EXPECT_EQ(stress_case_limits("cmu_3x").max_damped_per_step, 1.0);
  EXPECT_EQ(stress_case_limits("fall_on_floor").max_penetration_mm, 5.0);
  EXPECT_EQ(stress_case_limits("box_press").max_penetration_mm, 10.0);
  EXPECT_LT(stress_case_limits("shake").max_penetration_mm, 0.0);
  for (const std::string& name : stress_suite_case_names()) EXPECT_EQ(stress_case_limits(name).max_rejected, 0) << name;
  EXPECT_THROW(stress_case_limits("walkabout"), Error);

  // A shake run that damped 2 % of its steps (the fixed joint springs' regression) is a failed case.
  StressReport r = crafted_run(std::vector<double>(1000, 20.0), 100);
  r.damped = 20;
  StressOptions o = options();
  o.max_damped_per_step = stress_case_limits("shake").max_damped_per_step;
  judge_stress(r, o);
  const StressCaseResult c = stress_case_result("shake@1/30", "builtin:shake", 1.0 / 30, r, true);
  EXPECT_EQ(c.status, "FAILED");
  EXPECT_NE(c.message.find("20 damped Newton iterations in 1000 steps"), std::string::npos) << c.message;
}

TEST(StressChecks, ScenePenetrationBeyondItsLimitFails) {
  const StressCaseLimits floor = stress_case_limits("fall_on_floor");
  StressCaseResult c;
  c.max_penetration_mm = 4.2;  // the recorded figure
  check_stress_case_penetration(c, floor);
  EXPECT_EQ(c.status, "ok");
  c.max_penetration_mm = 5.5;
  check_stress_case_penetration(c, floor);
  EXPECT_EQ(c.status, "FAILED");
  EXPECT_EQ(c.message, "penetration 5.50 mm (at most 5.0 mm)");
  StressCaseResult none;  // a scene with a limit but no contact pair recorded
  check_stress_case_penetration(none, floor);
  EXPECT_EQ(none.status, "FAILED");
  StressCaseResult nan;
  nan.max_penetration_mm = std::numeric_limits<double>::quiet_NaN();
  check_stress_case_penetration(nan, floor);
  EXPECT_EQ(nan.status, "FAILED");
  StressCaseResult shake;  // no limit: not checked
  check_stress_case_penetration(shake, stress_case_limits("shake"));
  EXPECT_EQ(shake.status, "ok");
}

}  // namespace
