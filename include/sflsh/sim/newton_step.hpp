#pragma once
// Newton iterations on the backward-Euler objective E(q) = Σ_terms E_term(q)
// (Gast et al. 2015; seed §1): dense assembly over the DofLayout, Cholesky of
// the PSD Hessian (+ a relative diagonal shift only if it does not factor), step in
// the tangent space, retraction (configuration.hpp).
#include <vector>

#include "sflsh/sim/energy_term.hpp"
#include "sflsh/sim/step_report.hpp"

namespace sflsh {

struct NewtonOptions {
  /// Newton iterations per time step (1 = the paper's default).
  int iterations = 1;
  /// Stop early when ‖∂E/∂δ‖ falls below this (mixed units: N, N·m). 0 = never.
  double gradient_tolerance = 0.0;
  /// Backtracking line search on the total energy (Armijo, halving, up to 20 halvings).
  /// Off: the full step is taken unless it makes the energy inadmissible (+inf,
  /// e.g. an inverted element), in which case it is halved until admissible.
  bool line_search = false;
  /// Largest change of any handle displacement z_k per iteration (m); longer
  /// steps are scaled down as a whole (counted as damped). ≤ 0 disables.
  double max_z_step = 0.05;
  /// Largest bone rotation change per iteration (rad); ≤ 0 disables. Fast
  /// mocap (a jog's feet turn 0.66 rad per 1/60 s step) needs more than 0.5:
  /// a cap scales the whole step, pelvis included (CMU 16_46: pelvis error
  /// 25.5 mm at 0.5 rad, 1.6 mm at 1 rad; same figures with no cap).
  double max_rotation_step = 1.0;
  /// Diagonal regularization, used only when the Cholesky factorization of H
  /// itself fails (H is PSD by construction and PD when every DoF has mass):
  /// then H_ii ← H_ii (1 + ε), ε = this, multiplied by 100 (up to 6 times)
  /// until it factors. Relative per entry, so light DoFs are not biased.
  double regularization = 1e-10;
  /// Evaluate energy and gradient at the final configuration for the report
  /// (costs one gradient evaluation; needed for energy_after/grad_norm_after).
  bool report_final = true;
};

/// Runs Newton iterations from `q` (updated in place) on Σ terms at `ctx`.
/// All terms' begin_step must already have been called for this step.
StepReport newton_minimize(const std::vector<EnergyTerm*>& terms, const StepContext& ctx, Configuration& q,
                           const NewtonOptions& options);

/// Total energy Σ terms at q, adding gradient/Hessian when non-null (sized and
/// zeroed here); per-term values go to `per_term` when non-null, and each
/// term's evaluation time (ms) is added to `term_ms` (sized to #terms) when non-null.
double total_energy(const std::vector<EnergyTerm*>& terms, const StepContext& ctx, const Configuration& q,
                    VecX* grad, MatX* hess, std::vector<double>* per_term = nullptr,
                    std::vector<double>* term_ms = nullptr);

}  // namespace sflsh
