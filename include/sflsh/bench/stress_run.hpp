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
  /// Simulated pelvis vs the motion's root over the output frames (mm).
  double pelvis_error_max_mm = 0, pelvis_error_mean_mm = 0;
  double ms_median = 0;          ///< step wall time (ms)
  double peak_soft_mm_early = 0, peak_soft_mm_late = 0;  ///< first 10 % of windows, last window
  bool finite = true, stable = true, no_inversion = true;
  bool passed() const { return finite && stable && no_inversion; }
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
