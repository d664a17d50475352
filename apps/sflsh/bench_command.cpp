// `sflsh bench`: run time against error versus the full-FEM reference.
#include <tbb/global_control.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iostream>

#include "command.hpp"
#include "support_flags.hpp"
#include "sflsh/core/error.hpp"
#include "sflsh/bench/benchmark.hpp"
#include "sflsh/io/atomic_output.hpp"

namespace sflsh::cli {
namespace {

struct BenchArgs {
  bool quick = false, no_cache = false, peer = true;
  std::string motion = "builtin:jump", out = "bench", model = "procedural", betas, handles, cache_dir;
  std::vector<std::string> only;
  int inertia_samples_per_cell = PrecomputeOptions().inertia_samples_per_cell;
  int variants_handles = BenchOptions().default_handles;
  double seconds = 0;
  bool seconds_given = false;
  std::string support_spacing;  // dimensionless; empty = off
  std::string support_radius;          // m; empty = unrestricted supports
  std::string linear_solver = "dense";  // dense | sparse
  bool cpu_time = false;
};

void run_bench(const BenchArgs& a) {
  // Figures are for one core: no TBB or BLAS threads.
  setenv("OPENBLAS_NUM_THREADS", "1", 1);
  setenv("OMP_NUM_THREADS", "1", 1);
  tbb::global_control one_thread(tbb::global_control::max_allowed_parallelism, 1);

  BenchOptions o;
  o.quick = a.quick;
  o.peer = a.peer;
  o.motion = a.motion;
  o.seconds = a.seconds;
  o.model = a.model;
  o.only = a.only;
  require(a.inertia_samples_per_cell >= 0 && a.inertia_samples_per_cell <= 1000,
          "--inertia-samples-per-cell must be in [0, 1000], got ", a.inertia_samples_per_cell);
  o.precompute.inertia_samples_per_cell = a.inertia_samples_per_cell;
  apply_support_flags(a.support_radius, a.support_spacing, o.precompute.bbw);
  require(a.linear_solver == "dense" || a.linear_solver == "sparse", "--linear-solver must be dense or sparse, got '",
          a.linear_solver, "'");
  o.linear_solver = a.linear_solver == "sparse" ? LinearSolver::Sparse : LinearSolver::Dense;
  o.cpu_time = a.cpu_time;
  if (!a.betas.empty()) o.betas = parse_betas(a.betas);
  if (!a.handles.empty()) {
    VecX k;
    try {
      k = parse_betas(a.handles);  // same comma-separated number syntax
    } catch (const Error&) {
      fail("--handles '", a.handles, "': expected comma-separated whole numbers like 16,32,64");
    }
    for (Eigen::Index i = 0; i < k.size(); ++i) {
      require(k[i] >= 1 && k[i] <= 2000 && k[i] == std::floor(k[i]), "--handles: '", k[i],
              "' is not a whole number in [1, 2000] (as precompute --handles)");
      o.handle_counts.push_back(int(k[i]));
    }
  }
  require(a.variants_handles >= 1 && a.variants_handles <= 2000, "--variants-handles must be in [1, 2000], got ",
          a.variants_handles);
  o.default_handles = a.variants_handles;
  if (!a.no_cache) o.precompute.cache_dir = a.cache_dir.empty() ? default_cache_dir() : a.cache_dir;
  require(!a.seconds_given || (std::isfinite(a.seconds) && a.seconds > 0),
          "--seconds must be a positive number of seconds, got ", a.seconds);
  io::check_output_folder(a.out, "--out");

  const auto rows = run_benchmark(o);
  std::error_code ec;  // made only now: a run that fails leaves no empty folder
  std::filesystem::create_directories(a.out, ec);
  if (ec) fail("--out ", a.out, ": cannot create output folder: ", ec.message());
  const std::string csv = (std::filesystem::path(a.out) / "bench.csv").string();
  const std::string svg = (std::filesystem::path(a.out) / "bench.svg").string();
  const std::string md = (std::filesystem::path(a.out) / "bench.md").string();
  write_bench_csv(rows, csv);
  write_bench_markdown(rows, md);
  write_bench_plot_svg(rows, svg, "sflsh bench: " + a.motion + (a.quick ? " (quick)" : ""));
  std::printf("%-10s %-36s %4s %8s %6s %4s %9s %9s %8s %9s %9s %8s %6s\n", "method", "variant", "K", "dt", "iters",
              "def", "ms_med", "ms_p95", "speedup", "err_mm", "max_mm", "rel_err", "peak");
  for (const auto& r : rows)
    std::printf("%-10s %-36s %4d %8.5f %6d %4d %9.3f %9.3f %8.1f %9.3f %9.3f %8.3f %6.3f\n", r.method.c_str(),
                r.label.c_str(), r.handles, r.dt, r.newton_iters, r.is_default ? 1 : 0, r.ms_median, r.ms_p95,
                r.speedup, r.err_mean_mm, r.err_max_mm, r.rel_err, r.peak_ratio);
  std::printf("wrote %s, %s and %s\n", csv.c_str(), md.c_str(), svg.c_str());
}

const CommandRegistrar reg(50, [](CLI::App& app) {
  auto a = std::make_shared<BenchArgs>();
  auto* cmd = app.add_subcommand("bench", "Run time against error: reduced solver vs. full-FEM reference vs. skinning");
  cmd->add_flag("--quick", a->quick, "Fewer variants and 0.5 s of motion");
  cmd->add_option("--motion", a->motion, "Motion (builtin:jump|shake|idle or a file)")->capture_default_str();
  auto* seconds = cmd->add_option("--seconds", a->seconds, "Simulated seconds per variant (default 0.5 quick, 2 full)");
  cmd->add_option("--model", a->model, "Body model")->capture_default_str();
  cmd->add_option("--betas", a->betas, "Body shape b0,b1,...");
  cmd->add_option("--handles", a->handles, "Handle counts, e.g. 16,32,64,128");
  cmd->add_option("--variants-handles", a->variants_handles,
                  "K of the row marked default and of every variant row (time step, Newton, cubature...); added "
                  "to --handles if missing")
      ->capture_default_str();
  cmd->add_option("--cache-dir", a->cache_dir, "Template-stage cache folder");
  cmd->add_option("--only", a->only,
                  "Run only the variants whose label contains one of these strings (the reference, the default "
                  "and skinning always run), e.g. --only lumped,mass-fitted")
      ->delimiter(',');
  cmd->add_option("--inertia-samples-per-cell", a->inertia_samples_per_cell,
                  "Inertia cubature of every avatar built (as precompute --inertia-samples-per-cell)")
      ->capture_default_str();
  cmd->add_flag("--no-cache", a->no_cache, "Do not use the template-stage cache");
  cmd->add_flag("--peer,!--no-peer", a->peer, "Run the Bullet 3 deformable-FEM peer rows (default on)");
  cmd->add_option("--support-spacing", a->support_spacing,
                  "Compact support sized by the handle spacing: each handle's radius (along the tet edges) is this "
                  "factor times the distance to its nearest handle (as precompute --support-spacing)");
  cmd->add_option("--support-radius", a->support_radius,
                  "Compact-support basis for every avatar built (as precompute --support-radius, m)");
  cmd->add_option("--linear-solver", a->linear_solver,
                  "Newton system of the reduced rows: dense (Cholesky) or sparse (LDLT of the analysed pattern)")
      ->capture_default_str();
  cmd->add_flag("--cpu-time", a->cpu_time,
                "Reduced rows' ms per step as the stepping thread's CPU time (a machine shared with other jobs)");
  cmd->add_option("--out", a->out, "Output folder (bench.csv, bench.md, bench.svg)")->capture_default_str();
  cmd->callback([a, seconds] {
    a->seconds_given = seconds->count() > 0;
    run_bench(*a);
  });
});

}  // namespace
}  // namespace sflsh::cli
