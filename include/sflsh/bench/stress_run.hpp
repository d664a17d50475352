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
  /// Peak soft displacement over the last window may be at most this times
  /// the largest over the first 10 % of the run (no energy growth).
  double growth_limit = 1.5;
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
  double peak_soft_mm_early = 0, peak_soft_mm_late = 0;  ///< first 10 % of windows, last window
  /// finite: no non-finite state; complete: steps == planned_steps; stable:
  /// the last window's peak soft displacement ≤ growth_limit × the first 10 %
  /// of windows' (trivially true with one window, e.g. a 2× CMU clip);
  /// no_inversion: min det F > 0; tracking: pelvis_error_max_mm ≤ the tolerance.
  bool finite = true, complete = true, stable = true, no_inversion = true, tracking = true;
  bool passed() const { return finite && complete && stable && no_inversion && tracking; }
  std::string describe() const;
};

/// Runs the stress test (progress on stderr). Never throws on instability:
/// a non-finite state ends the run and is reported (finite = false). A motion
/// shorter than steps·dt ends the run early (report.steps says how many ran);
/// built-in motions are made long enough.
StressReport run_stress(std::shared_ptr<const Avatar> avatar, const StressOptions& options);

/// CSV (one row per window) and an SVG plot of peak soft displacement, elastic
/// energy and min det F over time.
void write_stress_csv(const StressReport& report, const std::string& path);
void write_stress_plot_svg(const StressReport& report, const std::string& path, const std::string& title);

}  // namespace sflsh
