#pragma once
// The run-time numerical guard: after a step, find the first
// non-finite value in the state or the step's energies and name where it is
// (the step, the energy term, the body), so that a run meeting NaN/Inf stops
// with one clear error instead of writing NaN frames.
#include <string>

#include "sflsh/core/error.hpp"
#include "sflsh/sim/model.hpp"
#include "sflsh/sim/state.hpp"
#include "sflsh/sim/step_report.hpp"

namespace sflsh {

/// What the guard found: empty `what` = everything finite.
struct NonFiniteReport {
  std::string body;  ///< the model body holding the first non-finite value ("" if none)
  std::string term;  ///< the first energy term whose value is non-finite ("" if every term is finite)
  std::string what;  ///< e.g. "reduced DoF z[12] = nan", "bone 3 (spine1) transform"; "" if all finite
  bool finite() const { return what.empty(); }
  /// "term 'elastic' of body 'avatar' is nan; body 'avatar': reduced DoF z[4] = nan".
  std::string describe() const;
};

/// Checks, in this order, every term energy of `report` (each named with the
/// first body it is bound to, through model.terms()) and every body's
/// configuration in `state` (bones' transforms, then z). Terms the step did not
/// evaluate (StepReport::energy_after NaN together with every term NaN, i.e.
/// NewtonOptions::report_final off) are not checked. Returns an empty report
/// when everything is finite.
NonFiniteReport find_non_finite(const Model& model, const State& state, const StepReport& report);

/// The error a run throws when the guard trips: the message names the step
/// (1-based) and its end time, the term and the body.
class NonFiniteError : public Error {
 public:
  NonFiniteError(const std::string& what, long step, NonFiniteReport report)
      : Error(what), step_(step), report_(std::move(report)) {}
  long step() const { return step_; }
  const NonFiniteReport& report() const { return report_; }

 private:
  long step_;
  NonFiniteReport report_;
};

/// Throws NonFiniteError "RUN: non-finite value at step STEP (t = T s): ...;
/// stopped (try a smaller --dt)" unless find_non_finite() finds everything
/// finite. `run` names the run in the message (a motion, a scene file).
void require_finite_step(const Model& model, const State& state, const StepReport& report, long step,
                         const std::string& run);

}  // namespace sflsh
