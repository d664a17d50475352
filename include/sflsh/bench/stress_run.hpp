#pragma once
// `sflsh stress`: a long run that must stay stable (issue: 10,000 steps of
// `shake` at dt = 1/30 s without NaN, explosion or inverted cubature
// elements). Bones dynamic with the skeleton terms, one Newton step per time
// step, as `sflsh simulate` runs by default. Every step records the smallest
// det F over the elastic cubature samples, the peak soft displacement of the
// skin and the energies; windows of steps summarize them for a table and plot.
#include <memory>
#include <string>
#include <vector>

#include "sflsh/asset/avatar.hpp"
#include "sflsh/scene/simulation_run.hpp"

namespace sflsh {

struct StressOptions {
  /// builtin:NAME (also builtin:torture, scene/torture_motion.hpp) or a motion file.
  std::string motion = "builtin:shake";
  double speed = 1;  ///< motion playback speed factor (> 0)
  double dt = 1.0 / 30.0;
  long steps = 10000;
  int window = 100;  ///< steps per summary window
  /// No energy growth: the peak soft displacement over the last window may be
  /// at most this times a reference taken earlier in the same run: a run of at
  /// least two full windows compares its last window with the first 10 %
  /// (growth_reference_share) of its windows.
  double growth_limit = 1.5;
  /// A run shorter than two windows (every CMU case: 11–60 steps) compares the
  /// largest peak of its last tenth of the steps (at least one) with every step
  /// before it, and may grow by this factor: a clip may end at its most violent
  /// motion (cmu_3x 09_03 on the default avatar ends at 69.6 mm, 1.84× every
  /// step before), while a run that blows up grows geometrically, step after
  /// step, far past it.
  double short_run_growth_limit = 3.0;
  /// The share of the windows, from the start, whose largest peak is the
  /// reference of a run of at least two full windows (0.1: the first 10 %).
  /// The suite's scenes use 0.5: their events (a landing, the body tipping
  /// over, a press) come in their first seconds, which in a run of a few
  /// hundred steps is more than its first tenth.
  double growth_reference_share = 0.1;
  /// Rejected steps allowed (a rejected step is a step that made no progress).
  long max_rejected = 0;
  /// Damped Newton iterations allowed per step, on average over the run.
  double max_damped_per_step = 1.0;
  /// The simulated pelvis may be at most this far from the motion's root
  /// after any step (mm; scripts/mocap_check.sh's 20 mm). ≤ 0: not checked.
  double pelvis_tolerance_mm = 20;
  /// Mean dilatation in the elastic term (SimulatorOptions::mean_dilatation, the default).
  bool mean_dilatation = true;
  /// NewtonOptions::iterations_after_damping (0: a damped step stays damped, as before).
  int iterations_after_damping = NewtonOptions{}.iterations_after_damping;
};

struct StressWindow {
  double t_end = 0;              ///< s
  double peak_soft_mm = 0;       ///< max over steps and skin vertices of |u|
  double max_elastic_J = 0;      ///< max elastic energy at the end of a step
  double min_det = 0;            ///< min det F over cubature samples and steps
  int damped = 0, rejected = 0;
  double ms_median = 0;
};

struct StressReport {
  std::vector<StressWindow> windows;
  long steps = 0;
  int accepted = 0, damped = 0, rejected = 0;
  double min_det = 0;            ///< over the whole run
  double peak_soft_mm = 0;       ///< over the whole run
  /// Simulated pelvis (joint 0) vs the motion's root after every step (mm): max, mean over the steps.
  double pelvis_error_max_mm = 0, pelvis_error_mean_mm = 0;
  long planned_steps = 0;        ///< steps the run should take (run_step_count)
  double ms_median = 0;          ///< step wall time (ms)
  /// Peak soft displacement after every step (mm; what the short-run growth check reads).
  std::vector<double> step_peak_soft_mm;
  /// The growth check's reference and late figures (StressOptions::growth_limit
  /// says which steps): early = the first 10 % of windows (growth_reference_share),
  /// or every step before the last tenth of a short run; late = last window, or
  /// that last tenth.
  double peak_soft_mm_early = 0, peak_soft_mm_late = 0;
  bool short_run = false;        ///< fewer than two full windows: the growth check used steps
  long max_rejected = 0;         ///< the limits judged against (StressOptions)
  double max_damped_per_step = 0, pelvis_tolerance_mm = 0, growth_limit = 0;
  /// finite: no non-finite state; complete: steps == planned_steps; stable:
  /// peak_soft_mm_late ≤ growth_limit (short_run_growth_limit for a short run)
  /// × peak_soft_mm_early; no_inversion:
  /// min det F > 0; tracking: pelvis_error_max_mm ≤ the tolerance;
  /// few_rejected: rejected ≤ max_rejected; few_damped: damped ≤
  /// max_damped_per_step × steps.
  bool finite = true, complete = true, stable = true, no_inversion = true, tracking = true, few_rejected = true,
       few_damped = true;
  bool passed() const {
    return finite && complete && stable && no_inversion && tracking && few_rejected && few_damped;
  }
  /// The first failed check in words ("" when passed), e.g. "3 rejected steps (at most 0)".
  std::string failure() const;
  std::string describe() const;
};

/// Runs the stress test (progress on stderr). Never throws on instability:
/// a non-finite state ends the run and is reported (finite = false). A motion
/// shorter than steps·dt ends the run early (report.steps says how many ran);
/// built-in motions are made long enough.
StressReport run_stress(std::shared_ptr<const Avatar> avatar, const StressOptions& options);

/// The checks of a finished run: fills min_det, peak_soft_mm, the growth
/// figures and every flag of `report` from its windows, step_peak_soft_mm,
/// counts, steps and planned_steps (set by run_stress; tests set them by hand)
/// and the limits of `options`.
void judge_stress(StressReport& report, const StressOptions& options);

/// CSV (one row per window) and an SVG plot of peak soft displacement, elastic
/// energy and min det F over time.
void write_stress_csv(const StressReport& report, const std::string& path);
void write_stress_plot_svg(const StressReport& report, const std::string& path, const std::string& title);

}  // namespace sflsh
