// `sflsh stress`: a long stability run (NaN, energy growth, inverted samples).
#include <cstdio>
#include <filesystem>

#include "command.hpp"
#include "sflsh/asset/avatar_file.hpp"
#include "sflsh/core/error.hpp"
#include "sflsh/core/time_step.hpp"
#include "sflsh/bench/stress_run.hpp"
#include "sflsh/io/atomic_output.hpp"

namespace sflsh::cli {
namespace {

struct StressArgs {
  std::string avatar, motion = "builtin:shake", dt = "1/30", out = "stress";
  long steps = 10000;
};

void run_stress_command(const StressArgs& a) {
  StressOptions o;
  o.motion = a.motion;
  o.dt = parse_time_step(a.dt);
  o.steps = a.steps;
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
  cmd->add_option("--motion", a->motion, "Motion (builtin:shake|jump|idle or a file)")->capture_default_str();
  cmd->add_option("--dt", a->dt, "Time step in seconds (e.g. 1/30)")->capture_default_str();
  cmd->add_option("--steps", a->steps, "Number of time steps")->capture_default_str();
  cmd->add_option("--out", a->out, "Output folder (stress.csv, stress.svg)")->capture_default_str();
  cmd->callback([a] { run_stress_command(*a); });
});

}  // namespace
}  // namespace sflsh::cli
