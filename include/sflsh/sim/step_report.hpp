#pragma once
// What one time step did (Ceres' Solver::Summary role): energies per term,
// residuals, Newton decrement, how many iterations were accepted as is, damped
// (step scaled by the step cap or the line search) or rejected, and timing.
#include <string>
#include <vector>

namespace sflsh {

/// Fate of one Newton iteration.
enum class StepOutcome : int {
  Accepted = 0,  ///< full Newton step taken
  Damped = 1,    ///< step scaled down (step cap, line search, or an inadmissible full step)
  Rejected = 2,  ///< no admissible/decreasing step found: configuration left unchanged
};

/// Name of an outcome ("accepted", "damped", "rejected").
const char* to_string(StepOutcome outcome);

struct TermEnergy {
  std::string name;
  double value = 0;  ///< J, at the end of the step
  double ms = 0;     ///< time spent evaluating this term during the step (all evaluations)
  bool active = true;  ///< false: the term sat this step out (value 0, no time)
};

/// A quantity a term reported after the step (e.g. a reaction force).
struct TermQuantityReport {
  std::string term;   ///< the term's name
  int body = 0;       ///< its first bound body
  std::string name, unit;
  std::vector<double> value;
  int term_index = -1;  ///< the term's index in the Model (Model::terms())
};

struct StepReport {
  double time = 0;                    ///< s, simulation time at the end of the step
  std::vector<TermEnergy> energies;   ///< per term, at the end of the step (J)
  std::vector<TermQuantityReport> quantities;  ///< what terms reported (EnergyTerm::report)
  double energy_before = 0;           ///< total objective at the start configuration (J)
  double energy_after = 0;            ///< total objective at the end (J; NaN if not evaluated)
  double grad_norm_before = 0;        ///< ‖∂E/∂δ‖ at the start (mixed N / N·m units)
  double grad_norm_after = 0;         ///< ‖∂E/∂δ‖ at the end (NaN if not evaluated)
  double newton_decrement = 0;        ///< √(δᵀ H δ) of the first iteration (√J)
  double step_scale = 1;              ///< scale applied to the last Newton step (1 = full)
  double regularization = 0;          ///< relative diagonal shift ε of the last solve (H_ii(1 + ε); 0 = none)
  int iterations = 0;                 ///< Newton iterations performed
  int sparse_solves = 0;              ///< of those, solved by the sparse factorization (NewtonOptions::linear_solver)
  int accepted = 0, damped = 0, rejected = 0;  ///< per-iteration outcome counts
  /// Of `iterations`, those added because the planned last one was damped
  /// (NewtonOptions::iterations_after_damping).
  int iterations_after_damping = 0;
  /// Of `iterations`, those added because the last planned one's energy
  /// change departed from the quadratic model (NewtonOptions::nonlinearity_tolerance).
  int iterations_for_nonlinearity = 0;
  StepOutcome outcome = StepOutcome::Accepted;  ///< worst outcome over the iterations
  double ms_assemble = 0;             ///< ms evaluating energies, gradients, Hessians
  double ms_solve = 0;                ///< ms in the Cholesky factorization and solve
  double ms_total = 0;                ///< ms for the whole step (including the final report evaluation)

  /// A few human-readable lines (Ceres-style summary).
  std::string summary() const;
};

}  // namespace sflsh
