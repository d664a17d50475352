// `sflsh stress`: a long stability run (NaN, energy growth, inverted samples).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>

#include "command.hpp"
#include "sflsh/asset/avatar_file.hpp"
#include "sflsh/core/error.hpp"
#include "sflsh/core/time_step.hpp"
#include "sflsh/bench/stress_run.hpp"
#include "sflsh/bench/stress_suite.hpp"
#include "sflsh/io/atomic_output.hpp"

namespace sflsh::cli {
namespace {

struct StressArgs {
  std::string avatar, motion = "builtin:shake", dt = "1/30", out = "stress";
  long steps = 10000;
  double speed = 1;
  bool mean_dilatation = StressOptions().mean_dilatation;
  int iterations_after_damping = StressOptions().iterations_after_damping;
};

struct SuiteArgs {
  std::string avatar, cases, out = "stress_suite", mocap_dir = "../shared/data/mocap/cmu", scenes_dir = "apps/scenes";
  long steps = 10000;
  int window = 100;
};

std::vector<std::string> split_commas(const std::string& s) {
  std::vector<std::string> out;
  size_t start = 0;
  while (start <= s.size()) {
    const size_t end = std::min(s.find(',', start), s.size());
    std::string item = s.substr(start, end - start);
    require(!item.empty(), "--cases: empty case name in '", s, "'");
    out.push_back(item);
    start = end + 1;
  }
  return out;
}

void run_suite_command(const SuiteArgs& a, const std::string& command_line) {
  StressSuiteOptions o;
  o.avatar_path = a.avatar;
  if (!a.cases.empty()) o.cases = split_commas(a.cases);
  o.steps = a.steps;
  o.window = a.window;
  o.mocap_dir = a.mocap_dir;
  o.scenes_dir = a.scenes_dir;
  validate_stress_suite_options(o);  // bad input fails before the avatar is read
  io::check_output_folder(a.out, "--out");
  const auto avatar = std::make_shared<const Avatar>(read_avatar(a.avatar));
  const std::filesystem::path dir(a.out);
  // The tables are rewritten after every case: a long suite stopped half-way keeps its finished cases.
  const std::vector<StressCaseResult> results =
      run_stress_suite(avatar, o, [&](const std::vector<StressCaseResult>& so_far) {
        std::error_code ec;
        std::filesystem::create_directories(a.out, ec);
        if (ec) fail("--out ", a.out, ": cannot create output folder: ", ec.message());
        write_stress_suite_csv(so_far, (dir / "stress_suite.csv").string());
        write_stress_suite_markdown(so_far, (dir / "stress_suite.md").string(), command_line);
        write_stress_suite_svg(so_far, (dir / "stress_suite.svg").string());
      });
  int failed = 0;
  for (const StressCaseResult& r : results) {
    std::printf("%-24s %-8s steps %6ld  NaN %d  rejected %4d  damped %4d  min det %.3f  peak soft %6.1f mm", r.name.c_str(),
                r.status.c_str(), r.steps, r.finite ? 0 : 1, r.rejected, r.damped, r.min_det, r.peak_soft_mm);
    if (r.pelvis_max_mm >= 0) std::printf("  pelvis max %.1f mm", r.pelvis_max_mm);
    if (!r.message.empty()) std::printf("  (%s)", r.message.c_str());
    std::printf("\n");
    failed += r.status == "FAILED";
  }
  std::printf("wrote %s/stress_suite.csv, .md and .svg\n", a.out.c_str());
  if (failed) fail("stress-suite: ", failed, " case(s) failed (see above)");
}

void run_stress_command(const StressArgs& a) {
  StressOptions o;
  o.motion = a.motion;
  o.dt = parse_time_step(a.dt);
  o.steps = a.steps;
  o.speed = a.speed;
  o.mean_dilatation = a.mean_dilatation;
  require(a.iterations_after_damping >= 0 && a.iterations_after_damping <= 100,
          "--iterations-after-damping must be in [0, 100], got ", a.iterations_after_damping);
  o.iterations_after_damping = a.iterations_after_damping;
  require(std::isfinite(a.speed) && a.speed > 0, "--speed must be positive, got ", a.speed);
  require(a.steps >= 1, "--steps must be >= 1, got ", a.steps);
  io::check_output_folder(a.out, "--out");
  const auto avatar = std::make_shared<const Avatar>(read_avatar(a.avatar));
  const StressReport r = run_stress(avatar, o);
  // Made only now, so that a run that fails to start (a missing motion) leaves no empty folder.
  std::error_code ec;
  std::filesystem::create_directories(a.out, ec);
  if (ec) fail("--out ", a.out, ": cannot create output folder: ", ec.message());
  const std::string csv = (std::filesystem::path(a.out) / "stress.csv").string();
  const std::string svg = (std::filesystem::path(a.out) / "stress.svg").string();
  write_stress_csv(r, csv);
  write_stress_plot_svg(r, svg, "sflsh stress: " + a.motion + ", dt " + a.dt + ", " + std::to_string(r.steps) + " steps");
  std::printf("%swrote %s and %s\n", r.describe().c_str(), csv.c_str(), svg.c_str());
  if (!r.passed()) fail("stress test failed (see above)");
}

const CommandRegistrar reg(55, [](CLI::App& app) {
  auto a = std::make_shared<StressArgs>();
  auto* cmd = app.add_subcommand("stress", "Long stability run: no NaN, no energy growth, no inverted cubature samples");
  cmd->add_option("--avatar", a->avatar, "Avatar file from `sflsh precompute`")->required();
  cmd->add_option("--motion", a->motion, "Motion (builtin:shake|jump|idle|walk|torture or a file)")->capture_default_str();
  cmd->add_option("--speed", a->speed, "Motion playback speed factor")->capture_default_str();
  cmd->add_option("--dt", a->dt, "Time step in seconds (e.g. 1/30)")->capture_default_str();
  cmd->add_option("--steps", a->steps, "Number of time steps")->capture_default_str();
  cmd->add_option("--out", a->out, "Output folder (stress.csv, stress.svg)")->capture_default_str();
  cmd->add_flag("--mean-dilatation,!--volume-per-tet", a->mean_dilatation,
                "Average the elastic volume change per cell (the default; as `simulate --mean-dilatation`)");
  cmd->add_option("--iterations-after-damping", a->iterations_after_damping,
                  "Newton iterations added to a step whose last one was damped (as in `simulate`; 0: none)")
      ->capture_default_str();
  cmd->callback([a] { run_stress_command(*a); });
});

const CommandRegistrar reg_suite(56, [](CLI::App& app) {
  auto a = std::make_shared<SuiteArgs>();
  auto* cmd = app.add_subcommand("stress-suite",
                                 "Stability suite: shake at two dt, the torture motion, CMU clips sped up, contact scenes; "
                                 "CSV + markdown + SVG");
  cmd->add_option("--avatar", a->avatar, "Avatar file from `sflsh precompute`")->required();
  cmd->add_option("--cases", a->cases,
                  "Comma-separated NAME[@DT] (shake, torture, cmu_2x, cmu_3x, fall_on_floor, box_press); default: "
                  "shake@1/30,shake@1/15,torture@1/30,cmu_2x@1/30,cmu_3x@1/30,fall_on_floor,box_press");
  cmd->add_option("--steps", a->steps, "Time steps per case (CMU clips: their own length)")->capture_default_str();
  cmd->add_option("--window", a->window, "Steps per summary window (plot)")->capture_default_str();
  cmd->add_option("--mocap-dir", a->mocap_dir, "Folder of CMU .bvh files (missing: the CMU cases are skipped)")
      ->capture_default_str();
  cmd->add_option("--scenes-dir", a->scenes_dir, "Folder of the scene files")->capture_default_str();
  cmd->add_option("--out", a->out, "Output folder (stress_suite.csv, .md, .svg)")->capture_default_str();
  cmd->callback([a] {
    std::string line = "sflsh stress-suite --avatar " + a->avatar + " --steps " + std::to_string(a->steps);
    if (!a->cases.empty()) line += " --cases " + a->cases;
    run_suite_command(*a, line);
  });
});

}  // namespace
}  // namespace sflsh::cli
