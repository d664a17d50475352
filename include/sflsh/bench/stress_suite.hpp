#pragma once
// `sflsh stress-suite`: a set of long stability cases on one
// avatar, each reported with the same figures: non-finite state, rejected and
// damped steps, smallest det F over the elastic cubature samples, peak soft
// displacement of the skin, and the pelvis error against the motion's root
// where a motion root exists (dynamic bones following a motion).
//
// Cases: "NAME" or "NAME@DT" (DT as parse_time_step reads it, e.g. 1/30):
//   shake          builtin:shake, bones dynamic (dt default 1/30 s)
//   torture        builtin:torture (scene/torture_motion.hpp), bones dynamic (1/30 s)
//   cmu_2x, cmu_3x every .bvh of the mocap folder played 2× / 3× as fast
//                  (1/30 s), one row per clip, each for its whole length
//                  (0.5–2 s at 2×, not 10⁴ steps); skipped with a message when
//                  the folder has no .bvh files
//   fall_on_floor, box_press   the scene files of that name in the scenes
//                  folder (apps/scenes), run through the scene code with the
//                  suite's avatar and the scene's solver (@DT overrides its
//                  dt) for `steps` steps; det F and soft displacement sampled
//                  every `window` steps
// The default list: shake@1/30, shake@1/15, torture@1/30, cmu_2x@1/30,
// cmu_3x@1/30, fall_on_floor, box_press.
//
// A case passes when its state stays finite, it runs every planned step, no
// cubature sample inverts (det F > 0), the soft displacement does not grow
// (StressOptions::growth_limit, short_run_growth_limit in a run shorter than
// two windows; scenes: per output frame, one per window or, in a run shorter
// than two windows, one per step),
// the pelvis stays within 20 mm of the motion's root (motion cases), and it
// stays within its limits (stress_case_limits): rejected steps, damped Newton
// iterations per step and, for the scenes, the deepest penetration of any
// contact pair.
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "sflsh/asset/avatar.hpp"
#include "sflsh/bench/stress_run.hpp"

namespace sflsh {

/// What a case may not exceed (besides the checks every case has, above).
struct StressCaseLimits {
  long max_rejected = 0;             ///< rejected steps
  double max_damped_per_step = 1;    ///< damped Newton iterations per step, on average
  double max_penetration_mm = -1;    ///< deepest penetration of any contact pair (scenes; < 0: not checked)
};

/// The limits of case `name` (without @DT), from the recorded suites
/// (scripts/results/stress_suite*.md) with room above them:
///   shake          0 rejected, ≤ 0.01 damped per step (recorded: 0; 1,666 in 10⁴
///                  steps before the joint springs were sized by the flesh they move)
///   torture        0 rejected, ≤ 2 damped per step (the targets jump by ~3 rad every
///                  0.2 s and the rotation cap is what holds them: recorded 0.91–0.92
///                  at 1/30 on the default body, 1.36 at 1/15 on the synthetic test
///                  body; a step has at most 1 + iterations_after_damping = 4)
///   cmu_2x, cmu_3x 0 rejected, ≤ 1 damped per step (recorded ≤ 0.82, 9 in 11 steps)
///   fall_on_floor  0 rejected, ≤ 1 damped per step (the damped iterations come with
///                  the landing, so their share depends on the run's length: 0.013–0.061
///                  over 10⁴ steps, 0.15 over 600 on a coarse body), penetration ≤ 5 mm
///                  (scripts/contact_figures.py's target; recorded 3.85–4.2 mm)
///   box_press      0 rejected, ≤ 1 damped per step (recorded ≤ 0.002 over 10⁴ steps,
///                  0.04 over 600), penetration ≤ 10 mm (the box goes 20 mm into the
///                  belly; recorded 4.75–4.84 mm)
/// Throws sflsh::Error for an unknown name.
StressCaseLimits stress_case_limits(const std::string& name);

/// The case names (without @DT).
const std::vector<std::string>& stress_suite_case_names();
/// The cases run when none are given.
const std::vector<std::string>& stress_suite_default_cases();

/// One parsed case spec.
struct StressCaseSpec {
  std::string spec;   ///< as given, e.g. "shake@1/15"
  std::string name;   ///< e.g. "shake"
  double dt = 0;      ///< s; 0 = the case's default
};
/// Parses "NAME[@DT]": throws one sflsh::Error naming `option`, the spec and
/// the known names for an unknown name, or the bad time step.
StressCaseSpec parse_stress_case(const std::string& spec, const std::string& option = "--cases");

struct StressSuiteOptions {
  std::string avatar_path;          ///< the avatar file (scenes load it themselves)
  std::vector<std::string> cases;   ///< "NAME[@DT]"; empty = stress_suite_default_cases()
  long steps = 10000;               ///< per case (CMU clips: their own length)
  int window = 100;                 ///< steps per summary window
  std::string mocap_dir;            ///< folder of CMU .bvh files
  std::string scenes_dir;           ///< folder of the scene files (fall_on_floor.yaml, box_press.yaml)
};

/// Figures of one case (or one CMU clip of a case).
struct StressCaseResult {
  std::string name;                 ///< the spec, with the clip for CMU: "shake@1/30", "cmu_2x@1/30/16_46"
  std::string setup;                ///< what ran (motion, dt, bones)
  std::string status = "ok";        ///< ok | FAILED | skipped
  std::string message;              ///< why skipped/failed
  double dt = 0;
  long steps = 0;
  bool finite = true;
  int rejected = 0, damped = 0;
  double min_det = 0;               ///< smallest det F over cubature samples
  double peak_soft_mm = 0;
  double pelvis_max_mm = -1, pelvis_mean_mm = -1;  ///< < 0: no motion root
  double ms_median = 0;
  double max_penetration_mm = -1;   ///< scenes: deepest penetration of any contact pair; < 0: none
  double peak_soft_mm_early = 0, peak_soft_mm_late = 0;  ///< the growth check's figures (StressReport)
  std::vector<double> window_t, window_peak_soft_mm;  ///< per window, for the plot
};

/// The result of a case from its stress report (`has_root`: the pelvis error
/// is against a motion root): status FAILED with report.failure() as the
/// message unless report.passed().
StressCaseResult stress_case_result(const std::string& name, const std::string& setup, double dt,
                                    const StressReport& report, bool has_root);
/// Marks `result` FAILED (unless it failed already) when its max_penetration_mm
/// exceeds limits.max_penetration_mm (≥ 0) or is not finite.
void check_stress_case_penetration(StressCaseResult& result, const StressCaseLimits& limits);

/// Validates the options (every case spec parses, steps/window >= 1): throws
/// one sflsh::Error naming the option and the accepted values.
void validate_stress_suite_options(const StressSuiteOptions& options);

/// Runs the cases (progress on stderr). A case whose run throws (a missing
/// scene file) is recorded as FAILED with the message; the suite goes on.
/// `on_case` (if given) sees the results so far after every case (e.g. to
/// write the tables as the suite goes).
std::vector<StressCaseResult> run_stress_suite(
    std::shared_ptr<const Avatar> avatar, const StressSuiteOptions& options,
    const std::function<void(const std::vector<StressCaseResult>&)>& on_case = {});

/// The results as CSV (one row per case), a markdown table, and an SVG plot
/// of the peak soft displacement per window over time (one line per case).
void write_stress_suite_csv(const std::vector<StressCaseResult>& results, const std::string& path);
void write_stress_suite_markdown(const std::vector<StressCaseResult>& results, const std::string& path,
                                 const std::string& command);
void write_stress_suite_svg(const std::vector<StressCaseResult>& results, const std::string& path);

}  // namespace sflsh
