#pragma once
// Newton iterations on the backward-Euler objective E(q) = Σ_terms E_term(q)
// (Gast et al. 2015; seed §1): dense assembly over the DofLayout, Cholesky of
// the PSD Hessian (+ a relative diagonal shift only if it does not factor), step in
// the tangent space, retraction (configuration.hpp).
#include <memory>
#include <optional>
#include <vector>

#include "sflsh/sim/energy_term.hpp"
#include "sflsh/sim/sparse_hessian_solve.hpp"
#include "sflsh/sim/step_report.hpp"

namespace sflsh {

/// NewtonOptions::nonlinearity_tolerance when unset and every DoF is soft tissue.
constexpr double kAutoNonlinearityTolerance = 0.05;

/// How the Newton system H δ = −g is factored.
enum class LinearSolver {
  Dense,  ///< Cholesky of the dense H (the default)
  /// Sparse LDLᵀ of H's nonzero pattern, analysed once per system
  /// (sim/sparse_hessian_solve.hpp); pays with compactly supported handle
  /// weights. Falls back to Dense for a step whose pattern is too dense or
  /// whose H does not factor without a shift.
  Sparse,
};

struct NewtonOptions {
  /// Newton iterations per time step (1 = the paper's default).
  int iterations = 1;
  /// Stop early when ‖∂E/∂δ‖ falls below this (mixed units: N, N·m). 0 = never.
  double gradient_tolerance = 0.0;
  /// Backtracking line search on the total energy (Armijo, halving, up to 20 halvings).
  /// Off: the full step is taken unless it makes the energy inadmissible (+inf,
  /// e.g. an inverted element), in which case it is halved until admissible.
  /// With it, a step whose line search finds no decrease while the predicted
  /// one, −gᵀδ, is below 1e-12·max(1, |E|) ends the iterations as converged
  /// (the iterate is kept) instead of counting as rejected.
  bool line_search = false;
  /// Largest change of any handle displacement z_k per iteration (m); longer
  /// steps are scaled down as a whole, bones included (counted as damped).
  /// ≤ 0 disables.
  double max_z_step = 0.05;
  /// Largest bone rotation change per iteration (rad); ≤ 0 disables. When a
  /// bone is over it, two steps are tried (sim/step_cap.hpp) and the one of
  /// lower energy is taken (counted as damped): the per-bone cap (that bone
  /// turns by the cap about the same axis, its joint moving as in the full
  /// step; the other bones and z take their full step) and the whole step
  /// scaled to the cap. The whole step alone held the pelvis back when a toe
  /// was over the cap (CMU at 2×, dt = 1/30: up to 67 mm); the per-bone cap
  /// alone shears the flesh on targets jumping ~3 rad (builtin:torture).
  double max_rotation_step = 1.0;
  /// When the last planned iteration was damped (a cap scaled it, or a halving
  /// made it admissible), up to this many more iterations are taken, stopping
  /// at the first one taken in full. A cap bounds how far one linearization is
  /// trusted; it must not also bound how far the bones get within a time step:
  /// with one iteration, a capped step left the pelvis up to 21 mm behind its
  /// motion (CMU 02_04 at 2×, dt = 1/30) and the lag went unnoticed.
  /// Steps that are not damped are untouched (bit-identical). 0 = off.
  int iterations_after_damping = 3;
  /// When the last planned iteration was taken in full but the energy fell by
  /// a share ρ of what the quadratic model predicted (½ δᵀHδ) with |ρ − 1|
  /// above this, one more iteration is taken (with the Armijo line search):
  /// the step went far enough into the nonlinear range that one
  /// linearization misses (a CMU run's foot strikes). ρ costs
  /// nothing, the trial energy is evaluated anyway. With bones prescribed,
  /// |ρ − 1| stays ≤ 0.046 on `jump` (where a second iteration changes
  /// nothing) and exceeds 0.05 on about a quarter of the steps of `shake` and
  /// a CMU run. Contact terms are left out (EnergyTerm::in_nonlinearity_check):
  /// then the other terms' change is compared with their own quadratic model,
  /// and the departure counted as a share of the whole step's predicted decrease.
  /// 0 = off.
  /// Unset (the default): kAutoNonlinearityTolerance when every DoF of the
  /// step is soft tissue (bones prescribed, no dynamic rigid object or tool), off
  /// otherwise: dynamic bones' rotations make ρ depart from 1 on most steps of
  /// any motion (|ρ − 1| > 0.1 on 56 % of `jump`'s, and as often for the soft
  /// DoFs' share of the step alone), so the check would double those steps.
  std::optional<double> nonlinearity_tolerance;
  /// Diagonal regularization, used only when the Cholesky factorization of H
  /// itself fails (H is PSD by construction and PD when every DoF has mass):
  /// then H_ii ← H_ii (1 + ε), ε = this, multiplied by 100 (up to 6 times)
  /// until it factors. Relative per entry, so light DoFs are not biased.
  double regularization = 1e-10;
  /// Factorization of the Newton system (LinearSolver).
  LinearSolver linear_solver = LinearSolver::Dense;
  /// LinearSolver::Sparse: factor sparsely whatever the pattern's density and
  /// cost (tests of the sparse path on bodies too small for it to pay).
  bool sparse_always = false;
  /// Evaluate energy and gradient at the final configuration for the report
  /// (costs one gradient evaluation; needed for energy_after/grad_norm_after).
  bool report_final = true;
};

/// Where a term's local system (its blocks, concatenated) sits in the global
/// step vector: pieces (global offset, size) in local order.
struct TermPlacement {
  std::vector<std::pair<int, int>> ranges;
  int local_size = 0;      ///< Σ sizes
  bool contiguous = true;  ///< one global interval [offset, offset + local_size): written in place
  int offset = 0;          ///< its start when contiguous
  /// Placement of the given pieces (sizes > 0).
  static TermPlacement from_ranges(std::vector<std::pair<int, int>> ranges);
};

/// One term of a step's system: the term, its context for this step, its placement.
struct SystemTerm {
  const EnergyTerm* term = nullptr;
  StepContext* ctx = nullptr;  ///< ctx->bound[i].q is pointed at the iterate before each evaluation
  TermPlacement placement;
  bool active = true;          ///< inactive terms are skipped (energy 0, no time)
};

/// The objective of one time step: Σ of the active terms over the bodies'
/// configurations. The assembler adds each term's local gradient/Hessian into
/// the global ones: in place through views when its placement is contiguous,
/// else through `scratch` and a scatter.
struct StepSystem {
  std::vector<SystemTerm> terms;
  std::vector<DofLayout> bodies;  ///< each body's global layout (retraction, step caps)
  int size = 0;                   ///< global step vector size
  VecX scratch_grad;              ///< scratch of scattered terms (reused)
  MatX scratch_hess;
  /// LinearSolver::Sparse: the analysed pattern, kept across steps (created on first use).
  std::shared_ptr<SparseHessianSolver> sparse_solver;
};

/// Σ active terms at q (one Configuration per body), adding gradient/Hessian
/// when non-null (sized and zeroed here); per-term values go to `per_term`
/// (0 for inactive terms) when non-null, and each term's evaluation time (ms)
/// is added to `term_ms` (sized to #terms) when non-null.
double total_energy(StepSystem& system, const std::vector<Configuration>& q, VecX* grad, MatX* hess,
                    std::vector<double>* per_term = nullptr, std::vector<double>* term_ms = nullptr);

/// Runs Newton iterations from `q` (one Configuration per body, updated in
/// place) on `system`. Every term's begin_step must already have been called.
StepReport newton_minimize(StepSystem& system, std::vector<Configuration>& q, const NewtonOptions& options);

/// One body and terms sharing one context (every term's local system is the
/// whole body, ctx.layout): the single-avatar form, for tests and tools. Calls
/// each term's begin_step itself (with a fresh cache, begin_term_step).
StepReport newton_minimize(const std::vector<EnergyTerm*>& terms, const StepContext& ctx, Configuration& q,
                           const NewtonOptions& options);

}  // namespace sflsh
