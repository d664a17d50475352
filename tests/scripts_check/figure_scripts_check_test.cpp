// The figure scripts judge their own figures (DESIGN.md §6): each one's --check
// mode on a crafted result folder (tests/scripts_check/make_figure_results.py,
// no simulation) must pass the "good" folder, exit 1 naming the row when one
// target is missed, and exit 2 with one line naming the file and the
// column/dataset/line when a result file is missing or malformed (no table).
// The missed-target cases are the defects these checks replaced: a yank
// energy that grows over the last 10 s (the old `late.max() <= e.max()` was
// always true), NaN in a tool log (the old NaN column was a literal "none"),
// frames behind at RTF 1, a slanted floor force with a positive vertical part,
// a surviving batch worker.
#include <gtest/gtest.h>

#include <filesystem>
#include <ostream>
#include <string>
#include <vector>

#include "test_support.hpp"

using namespace sflsh;

namespace {

const char* kPython = "/usr/bin/python3";

struct Case {
  std::string kind;     ///< make_figure_results.py KIND
  std::string variant;  ///< its VARIANT
  int exit_code;        ///< 0 met, 1 a target missed, 2 bad input
  std::vector<std::string> fragments;  ///< in the output (stderr for 1 and 2)
};

void PrintTo(const Case& c, std::ostream* os) { *os << c.kind << " " << c.variant; }

std::string check_command(const std::string& kind, const std::string& dir) {
  const std::string scripts = test::source_dir() + "/scripts/";
  if (kind == "teleop") return std::string(kPython) + " " + scripts + "teleop_figures.py --check " + dir;
  if (kind == "contact") return std::string(kPython) + " " + scripts + "contact_figures.py --check " + dir;
  if (kind == "patch_stress") return std::string(kPython) + " " + scripts + "patch_stress.py --check " + dir;
  if (kind == "fit") return std::string(kPython) + " " + scripts + "fit_benchmark.py --check " + dir;
  if (kind == "fit_dynamic") return std::string(kPython) + " " + scripts + "fit_dynamic_bones.py --check " + dir;
  if (kind == "sparse_subspace")
    return std::string(kPython) + " " + scripts + "sparse_subspace.py --no-run --work " + dir + " --out " + dir +
           "/sparse_subspace.md";
  if (kind == "batch_benchmark")
    return std::string(kPython) + " " + scripts + "batch_benchmark.py --check " + dir + "/checks.json";
  return "bash " + scripts + "batch_resume_check.sh --check " + dir + "/figures.txt";
}

class FigureScriptCheck : public ::testing::TestWithParam<Case> {};

TEST_P(FigureScriptCheck, JudgesTheCraftedFolder) {
  const Case& c = GetParam();
  std::string out;
  if (test::run_command(std::string(kPython) + " -c 'import numpy, h5py'", &out) != 0)
    GTEST_SKIP() << kPython << " lacks numpy or h5py (scripts/setup.sh installs python3-numpy python3-h5py): " << out;
  test::TempDir dir;
  const std::string folder = dir.file("results");
  ASSERT_EQ(test::run_command(std::string(kPython) + " " + test::source_dir() +
                                  "/tests/scripts_check/make_figure_results.py " + c.kind + " " + c.variant + " " + folder,
                              &out),
            0)
      << out;
  const int code = test::run_command(check_command(c.kind, folder), &out);
  EXPECT_EQ(code, c.exit_code) << out;
  for (const std::string& f : c.fragments) EXPECT_NE(out.find(f), std::string::npos) << "'" << f << "' in\n" << out;
  if (c.exit_code == 2) {  // one line, no table
    ASSERT_FALSE(out.empty());
    EXPECT_EQ(out.find('\n'), out.size() - 1) << out;
    EXPECT_EQ(out.find("| figure |"), std::string::npos) << out;
  }
  if (c.exit_code == 0) EXPECT_EQ(out.find("**no**"), std::string::npos) << out;
  if (c.exit_code == 1 && (c.kind == "teleop" || c.kind == "contact" || c.kind == "patch_stress" ||
                          c.kind == "fit_dynamic"))  // the table is printed, the row marked
    EXPECT_NE(out.find("**no**"), std::string::npos) << out;
}

std::string name_of(const ::testing::TestParamInfo<Case>& info) {
  return info.param.kind + "_" + info.param.variant;
}

INSTANTIATE_TEST_SUITE_P(
    Teleop, FigureScriptCheck,
    ::testing::Values(
        Case{"teleop", "good", 0, {"| 0 (RTF 1.000;", "66.6 J / 64.0 J", "| 2.50 N |"}},
        Case{"teleop", "pinch_slips", 1, {"target missed: pinch-and-lift", "2.80 mm"}},
        Case{"teleop", "pinch_no_return", 1, {"target missed: skin against the same run", "/ 0.70 / 1.20 mm"}},
        Case{"teleop", "pinch_ends_early", 2, {"pinch_coupled.h5: the run ends 1.13 s after the release"}},
        Case{"teleop", "pinch_nan", 1, {"target missed: grasp / release", ", NaN (target"}},
        Case{"teleop", "realtime_behind", 1, {"target missed: real time", "frames behind: 3 (RTF 1.000"}},
        Case{"teleop", "probe_behind", 1, {"target missed: real time: one avatar + a coupled 1 cm probe", "2 (RTF 1.000"}},
        Case{"teleop", "yank_energy_grows", 1, {"target missed: abuse: gripper yanked", "84.0 J"}},
        Case{"teleop", "yank_nan", 1, {"target missed: abuse: gripper yanked", "10000, NaN, 0"}},
        Case{"teleop", "hard_energy_grows", 1, {"target missed: abuse: anchors of hardness", "1.08 / 1.50 J"}},
        Case{"teleop", "hard_nan", 1, {"target missed: abuse: anchors of hardness", "10000, NaN, 0"}},
        Case{"teleop", "hard_missed_grasp", 1, {"target missed: abuse: anchors of hardness", ", 7, "}},
        Case{"teleop", "stream_energy_grows", 1, {"target missed: abuse: live stream", "1.08 / 2.00 J"}},
        Case{"teleop", "stream_nan", 1, {"target missed: abuse: live stream", "20.00 s, NaN"}},
        Case{"teleop", "stream_accepts_bad", 1, {"target missed: what the stream saw", "rejected 0"}},
        Case{"teleop", "yank_missing_column", 2, {"yank_tools.csv: column 'elastic_energy' missing"}},
        Case{"teleop", "hard_malformed_value", 2, {"hard_tools.csv line 7: column 'time': '0.1x' is not a number"}},
        Case{"teleop", "realtime_no_steps_line", 2, {"realtime.log: no 'steps: N accepted"}},
        Case{"teleop", "realtime_no_replay", 2, {"realtime_replay.json: cannot read"}},
        Case{"teleop", "pinch_open_shape", 2, {"pinch_open.h5: dataset '/frames/displacement' has shape"}}),
    name_of);

INSTANTIATE_TEST_SUITE_P(
    Contact, FigureScriptCheck,
    ::testing::Values(
        Case{"contact", "good", 0, {"664 N up, |horizontal| 2.5 N (0.0038) | yes", "0 / 0, 103 N | yes"}},
        Case{"contact", "floor_force_slanted", 1, {"target missed: floor force at rest", "200.0 N (0.3012)"}},
        Case{"contact", "floor_nan", 1, {"target missed: rejected steps, NaN: 0, NaN"}},
        Case{"contact", "slab_force_off", 1, {"target missed: slab (2 kg)", "0.9001"}},
        Case{"contact", "momentum_lost", 1, {"target missed: two-body collision", "1.2e-03"}},
        Case{"contact", "walkers_missing_line", 2, {"two_walkers.log: no 'contact skin_contact on alice"}},
        Case{"contact", "walker_spike", 1, {"target missed: peak contact force", "2500 N"}},
        Case{"contact", "ball_coarse_rejected", 1, {"target missed: ball_at_belly at 1/120 s", "0 / 82, 31992 N"}},
        Case{"contact", "walker_passes", 1, {"target missed: passes through", "yes"}},
        Case{"contact", "sphere_missing_dataset", 2, {"sphere_on_belly.h5: dataset '/frames/time' missing"}}),
    name_of);

INSTANTIATE_TEST_SUITE_P(
    FitAndBatch, FigureScriptCheck,
    ::testing::Values(
        Case{"fit", "good", 0, {"| forearm | x0.4 | x0.4040 | +1.0% ok"}},
        Case{"fit", "cmu_fung_missed", 1, {"target missed: cmu forearm fung_c: -27.2% (target ±10%)"}},
        Case{"fit", "cmu_no_iterations_line", 2, {"fit_cmu.log: no 'Iterations: N' line"}},
        Case{"fit_dynamic", "good", 0, {"| x1.9986 (-0.1 %) | yes", "x1.4533 (-27.3 %)", "0.495 → 0.047 mm"}},
        Case{"fit_dynamic", "own_missed", 1, {"target missed: belly Young's factor", "x2.1200 (+6.0 %)"}},
        Case{"fit_dynamic", "own_no_factor", 2, {"fit_own.log: no '  young:belly  xF ...' line"}},
        Case{"batch_resume", "good", 0, {"batch_resume_check: passed"}},
        Case{"batch_resume", "worker_survived", 1, {"1 worker process(es) outlived the killed batch"}},
        Case{"batch_resume", "not_identical", 1, {"5 of 6 files bit-identical"}},
        Case{"batch_resume", "rebuilt_done_rows", 1, {"the rerun kept 0 rows, 2 were done before the kill"}},
        Case{"batch_resume", "missing_key", 2, {"figures.txt: key 'identical' missing"}},
        Case{"batch_resume", "malformed_value", 2, {"figures.txt: key 'rerun_built': 'four' is not a count"}},
        Case{"batch_benchmark", "good", 0, {"batch_benchmark: passed"}},
        Case{"batch_benchmark", "jobs2_differs", 1, {"jobs2 wrote files different from serial's: avatar-0000000000000002.h5"}},
        Case{"batch_benchmark", "dask1_built_fewer", 1, {"dask1 built 3 of 4 shapes"}},
        Case{"batch_benchmark", "template_rewritten", 1, {"the template cache entry was rewritten"}},
        Case{"batch_benchmark", "missing_field", 2, {"checks.json: field 'template_cache_rewritten' missing"}},
        Case{"batch_benchmark", "malformed", 2, {"checks.json: not JSON"}}),
    name_of);

INSTANTIATE_TEST_SUITE_P(
    PatchStress, FigureScriptCheck,
    ::testing::Values(Case{"patch_stress", "good", 0, {"| 10000 / 0 | yes", "0.4520 J / 0.4500 J | yes"}},
                      Case{"patch_stress", "runaway", 1, {"target missed: elastic energy: largest over the run",
                                                          "78000.000 J"}},
                      Case{"patch_stress", "not_back", 1, {"target missed: elastic energy at the end (probe away)",
                                                           "0.6000 J / 0.4500 J"}},
                      Case{"patch_stress", "rejected", 1, {"target missed: steps taken / rejected: 10000 / 1"}},
                      Case{"patch_stress", "no_energy", 2, {"tools.csv: column 'elastic_energy' missing"}}),
    name_of);

INSTANTIATE_TEST_SUITE_P(
    SparseSubspace, FigureScriptCheck,
    ::testing::Values(Case{"sparse_subspace", "good", 0, {"Verdict: met by a compact-support row"}},
                      Case{"sparse_subspace", "slow", 1, {"**missed** by every compact-support row", "dynamic **no**"}},
                      Case{"sparse_subspace", "no_column", 2, {"t4_sp25_sparse/bench.csv: column rel_err_forearm"}}),
    name_of);

}  // namespace
