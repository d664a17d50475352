#pragma once
// `sflsh bench`: run time against error. On one avatar shape and one motion
// (bones prescribed, soft tissue dynamic) it runs the full-FEM reference
// (Newton to convergence, CHOLMOD), the reduced solver at several handle counts,
// time steps and Newton iteration counts, the Bullet 3 peer (bullet_peer.hpp;
// stopped at its first inverted tetra) and skinning only (u = 0), and
// compares the soft displacement of the skin in the simulated region at common
// frame times (30 per second).
//
//   rel_err    = ‖u − u_ref‖ / ‖u_ref‖  over simulated-region skin vertices and all frames
//   err_*_mm   = mean / max over those vertices and frames of |u − u_ref| (mm)
//   peak_ratio = max |u| / max |u_ref|
//   speedup    = reference median step time / method median step time
//   floor      = rel_err of the best approximation of the reference within the
//                row's basis span(W ⊗ I₃), mass-weighted least squares per frame
//                on the tet nodes (subspace_floor.hpp): the basis error alone
//   per region = rel_err and floor over the skin vertices of one body region
//                (the material region of the vertex's tet: belly, chest, ...)
#include <string>
#include <vector>

#include "sflsh/precompute/precompute.hpp"
#include "sflsh/sim/newton_step.hpp"

namespace sflsh {

struct BenchOptions {
  bool quick = false;                     ///< fewer variants, 0.5 s of motion
  bool peer = true;                       ///< the Bullet 3 peer rows (bullet_peer.hpp)
  std::string motion = "builtin:jump";
  double seconds = 0;                     ///< 0: 0.5 s quick, 2 s full
  std::string model = "procedural";
  VecX betas;
  std::vector<int> handle_counts;         ///< empty: quick {16, default}, full {16, 32, 64, 128}; the default K is added
  int default_handles = PrecomputeOptions().handles;
  double default_dt = 1.0 / 60.0;
  int converged_newton_iters = 20;        ///< the "Newton to convergence" variant
  PrecomputeOptions precompute;           ///< template/shape options (cache dir, ...)
  /// Factorization of the reduced rows' Newton systems (the full-FEM reference keeps CHOLMOD).
  LinearSolver linear_solver = LinearSolver::Dense;
  /// Reduced rows' ms per step (ms_median, p95, dynamic bones) as the stepping
  /// thread's CPU time instead of wall time: on a machine shared with other
  /// jobs it leaves out the time the thread waits for a core.
  bool cpu_time = false;
  /// Run only the variants whose label contains one of these strings (case
  /// sensitive); the reference, the default and skinning always run. Empty: all.
  std::vector<std::string> only;
};

/// rel_err of one body region (NaN when the region has no reference motion).
struct RegionError {
  std::string name;
  double rel_err = 0, floor_rel_err = 0;
};

struct BenchRow {
  std::string method;  ///< reference | reduced | peer | skinning
  std::string label;   ///< the variant in words (table, plot legend; not in the CSV)
  int handles = 0;
  double dt = 0;
  int newton_iters = 0;
  bool is_default = false;
  double ms_median = 0, ms_p95 = 0, speedup = 0;
  double err_mean_mm = 0, err_max_mm = 0, rel_err = 0, peak_ratio = 0;
  /// Subspace floor (reduced rows; NaN for the others, which have no basis).
  double floor_rel_err = 0;
  /// Per simulated body region, in the avatar's region order.
  std::vector<RegionError> regions;
  /// Reduced rows (NaN for the others): mean ms per step in the inertia and
  /// elastic terms and the Cholesky solve (prescribed bones, as ms_median);
  /// the median step with dynamic bones (skeleton terms, `sflsh simulate`'s
  /// default) on the same motion; and the peak memory the run added to the
  /// process (MiB above its resident size at the start of the run, model and
  /// state included; NaN where /proc cannot reset the peak).
  double ms_inertia = 0, ms_elastic = 0, ms_solve = 0, dynamic_ms_median = 0, peak_mib = 0;
};

/// Runs every variant (progress on stderr) and returns one row each.
std::vector<BenchRow> run_benchmark(const BenchOptions& options);

/// CSV with the header
/// method,handles,dt,newton_iters,is_default,ms_median,ms_p95,speedup,err_mean_mm,err_max_mm,rel_err,peak_ratio
/// followed by floor_rel_err and, per region of the first row, rel_err_<name>,floor_<name>.
void write_bench_csv(const std::vector<BenchRow>& rows, const std::string& path);
/// The rows as a Markdown table (with labels and the floor), then a table of
/// rel_err / floor per region, for the README.
void write_bench_markdown(const std::vector<BenchRow>& rows, const std::string& path);
/// Log-log scatter of rel_err against ms per step, as SVG.
void write_bench_plot_svg(const std::vector<BenchRow>& rows, const std::string& path, const std::string& title);

}  // namespace sflsh
