#pragma once
// Internals of the accuracy and speed benchmark (include/sflsh/bench/benchmark.hpp):
//   benchmark_traces.cpp   — the runs: full-FEM reference, reduced simulator, skinning
//                            only, the Bullet peer; each gives a Trace,
//   benchmark_errors.cpp   — a trace's errors against the reference, and basis floors,
//   benchmark_reports.cpp  — the rows as CSV, Markdown and an SVG plot,
//   benchmark.cpp          — the variants run and the rows they give.
#include "sflsh/bench/benchmark.hpp"

#include <malloc.h>

#include <algorithm>
#include <cmath>
#include <ctime>
#include <cstdio>
#include <fstream>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <string>

#include "sflsh/bench/bullet_peer.hpp"
#include "sflsh/bench/soft_tissue_modes.hpp"
#include "sflsh/bench/subspace_floor.hpp"
#include "sflsh/body/body_model_io.hpp"
#include "sflsh/core/error.hpp"
#include "sflsh/core/memory.hpp"
#include "sflsh/core/percentile.hpp"
#include "sflsh/core/progress.hpp"
#include "sflsh/core/timer.hpp"
#include "sflsh/fem/tet_operators.hpp"
#include "sflsh/motion/load_motion.hpp"
#include "sflsh/scene/simulation_run.hpp"
#include "sflsh/sim/energies/elastic.hpp"
#include "sflsh/reference/full_fem.hpp"
#include "sflsh/sim/posed_points.hpp"

namespace sflsh::bench_internal {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

/// Soft displacement of the skin at the comparison frames plus step timings.
struct Trace {
  std::vector<Points> u;      // per frame, #V by 3 (m)
  std::vector<double> ms;     // per step
  // Reduced runs: summed ms of the inertia and elastic terms and the solve; peak MiB added.
  double ms_inertia = 0, ms_elastic = 0, ms_solve = 0, peak_mib = std::numeric_limits<double>::quiet_NaN();
  std::vector<Points> nodal;  // reference only: per frame, #N by 3 nodal soft displacement (m)
};

/// The full-FEM reference (Newton to convergence) along the motion.
Trace run_reference(std::shared_ptr<const Avatar> avatar, const MotionClip& motion, double seconds, double h);

/// The reduced simulator along the motion with the given settings.
Trace run_reduced(std::shared_ptr<const Avatar> avatar, const MotionClip& motion, double seconds, double h,
                  int newton_iters, const std::string& label, bool bones_dynamic = false,
                  bool mean_dilatation = SimulatorOptions().mean_dilatation,
                  std::optional<double> nonlinearity_tolerance = std::nullopt,
                  LinearSolver linear_solver = LinearSolver::Dense, bool cpu_time = false);

/// The surface posed by the skeleton alone (u = 0): the cost of "doing nothing".
Trace run_skinning(const Avatar& a, const MotionClip& motion, double seconds, double h);

/// Skin vertices whose embedding tet has a Simulated node.
std::vector<int> simulated_region(const Avatar& a);

/// The skin's soft displacement (#V by 3) interpolated from nodal values (#N by 3).
Points surface_from_nodes(const Avatar& a, const Points& nodal);

/// The Bullet peer on the same mesh, bones and h (*diverged_at: the step that
/// inverted a tetra, else 0).
Trace run_peer(std::shared_ptr<const Avatar> avatar, const MotionClip& motion, double seconds, double h,
               bool rest_follows_skinning, int* newton_iterations, long* diverged_at);

/// The floor trace of basis W (a.W by default).
std::vector<Points> floor_trace(const Avatar& a, const Trace& ref,
                                const Eigen::SparseMatrix<double, Eigen::RowMajor>* W = nullptr);

/// Region label of each skin vertex in `region`, −1 elsewhere.
VecXi vertex_regions(const Avatar& a, const std::vector<int>& region);

/// Errors and step timings of `tr` against the reference over the skin vertices in `region`.
void compare(const Trace& tr, const Trace& ref, const std::vector<int>& region, BenchRow& row);

}  // namespace sflsh::bench_internal
