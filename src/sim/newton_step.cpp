#include "sflsh/sim/newton_step.hpp"

#include <cmath>
#include <limits>
#include <memory>
#include <optional>

#include <Eigen/Cholesky>

#include "sflsh/core/error.hpp"
#include "sflsh/core/timer.hpp"
#include "sflsh/sim/step_cap.hpp"

namespace sflsh {
namespace {

constexpr int kMaxHalvings = 20;
constexpr double kArmijo = 1e-4;

/// Each body's skeleton parent table, from the avatar of a term bound to it (null if none is).
std::vector<const std::vector<int>*> body_parents(const StepSystem& sys) {
  std::vector<const std::vector<int>*> parents(sys.bodies.size(), nullptr);
  for (const SystemTerm& t : sys.terms)
    for (const BoundBody& b : t.ctx->bound)
      if (b.avatar && b.slot >= 0 && b.slot < int(parents.size()) && !b.avatar->parents.empty())
        parents[b.slot] = &b.avatar->parents;
  return parents;
}

std::vector<Configuration> retract_all(const std::vector<Configuration>& q, const VecX& delta,
                                       const std::vector<DofLayout>& bodies) {
  std::vector<Configuration> out;
  out.reserve(q.size());
  for (size_t b = 0; b < q.size(); ++b) out.push_back(retract(q[b], delta, bodies[b]));
  return out;
}

/// Evaluates one term into the global gradient/Hessian (either may be null).
double evaluate_term(SystemTerm& t, const std::vector<Configuration>& q, VecX* grad, MatX* hess, VecX& g_local,
                     MatX& H_local) {
  StepContext& ctx = *t.ctx;
  for (BoundBody& b : ctx.bound) b.q = &q[b.slot];
  const Configuration& q0 = ctx.bound.empty() ? q[0] : q[ctx.bound[0].slot];
  const TermPlacement& p = t.placement;
  if (p.local_size == 0 || (!grad && !hess)) return t.term->compute(ctx, q0, nullptr, nullptr);
  // Views on the stack: no allocation per term and evaluation.
  std::optional<VecRef> g;
  std::optional<MatRef> H;
  if (p.contiguous) {
    if (grad) g.emplace(grad->segment(p.offset, p.local_size));
    if (hess) H.emplace(hess->block(p.offset, p.offset, p.local_size, p.local_size));
    return t.term->compute(ctx, q0, g ? &*g : nullptr, H ? &*H : nullptr);
  }
  // Scattered: fill a local system, then add each (piece, piece) block.
  if (grad) g_local.setZero(p.local_size);
  if (hess) H_local.setZero(p.local_size, p.local_size);
  if (grad) g.emplace(g_local);
  if (hess) H.emplace(H_local);
  const double e = t.term->compute(ctx, q0, g ? &*g : nullptr, H ? &*H : nullptr);
  int li = 0;
  for (const auto& [gi, ni] : p.ranges) {
    if (grad) grad->segment(gi, ni) += g_local.segment(li, ni);
    if (hess) {
      int lj = 0;
      for (const auto& [gj, nj] : p.ranges) {
        hess->block(gi, gj, ni, nj) += H_local.block(li, lj, ni, nj);
        lj += nj;
      }
    }
    li += ni;
  }
  return e;
}

/// Solves H δ = −g by Cholesky, in place in H (no copy of the ~n² matrix).
/// Every term's Hessian is PSD and the inertia terms make the sum PD whenever
/// every DoF carries mass, so no shift is tried first: a constant shift would
/// bias light DoFs (a finger bone's twist inertia / h² is ~1e-10 of the mean
/// diagonal). A DoF no term touches (H_ii = 0, so its row is 0 as H is PSD,
/// e.g. z when the soft-tissue terms are off) gets H_ii = 1: exact, it is
/// decoupled. If the factorization still fails, each diagonal entry is scaled
/// by (1 + ε), ε = `eps`·100^k, k = 0..6. H's lower triangle is overwritten;
/// its strict upper triangle and `diag` keep the original for a retry.
void solve_in_place(MatX& H, const VecX& g, double eps, VecX& delta, double* shift_used) {
  for (Eigen::Index i = 0; i < H.rows(); ++i)
    if (H(i, i) == 0.0) H(i, i) = 1.0;
  const VecX diag = H.diagonal();
  double shift = 0;
  for (int attempt = 0; attempt < 8; ++attempt) {
    if (attempt > 0) {
      H.triangularView<Eigen::StrictlyLower>() = H.transpose();
      H.diagonal() = diag + shift * diag.cwiseAbs();
    }
    Eigen::LLT<Eigen::Ref<MatX>> llt(H);
    if (llt.info() == Eigen::Success) {
      delta = -g;
      llt.solveInPlace(delta);
      if (delta.allFinite()) {
        *shift_used = shift;
        return;
      }
    }
    shift = attempt == 0 ? eps : shift * 100.0;
  }
  fail("newton_minimize: Hessian is not positive definite even with a relative diagonal shift of ", shift / 100.0,
       "; a DoF without any energy or a NaN in a term?");
}

/// Σ of `per_term` over the active terms the nonlinearity check leaves out.
double unchecked_energy(const StepSystem& sys, const std::vector<double>& per_term) {
  double E = 0;
  for (size_t i = 0; i < sys.terms.size() && i < per_term.size(); ++i)
    if (sys.terms[i].active && !sys.terms[i].term->in_nonlinearity_check()) E += per_term[i];
  return E;
}

/// Whether every DoF of the step is a body's soft tissue (z): no dynamic bone, rigid body or tool.
bool only_soft_dofs(const StepSystem& sys) {
  int soft = 0;
  for (const DofLayout& b : sys.bodies) soft += b.num_reduced;
  return soft == sys.size;
}

}  // namespace

TermPlacement TermPlacement::from_ranges(std::vector<std::pair<int, int>> ranges) {
  TermPlacement p;
  p.ranges = std::move(ranges);
  for (const auto& r : p.ranges) p.local_size += r.second;
  p.offset = p.ranges.empty() ? 0 : p.ranges[0].first;
  for (size_t i = 1; i < p.ranges.size(); ++i)
    if (p.ranges[i].first != p.ranges[i - 1].first + p.ranges[i - 1].second) p.contiguous = false;
  return p;
}

namespace {

/// What the terms left out of the nonlinearity check (EnergyTerm::
/// in_nonlinearity_check) add to an assembly: their gradient and Hessian,
/// also contained in the totals.
struct UncheckedPart {
  VecX g;
  MatX H;
};

/// total_energy; with `unchecked` (and grad, hess), the unchecked terms'
/// derivatives are also kept apart there.
double assemble(StepSystem& sys, const std::vector<Configuration>& q, VecX* grad, MatX* hess,
                std::vector<double>* per_term, std::vector<double>* term_ms, UncheckedPart* unchecked) {
  const int n = sys.size;
  if (grad) grad->setZero(n);
  if (hess) hess->setZero(n, n);
  const bool split = unchecked && grad && hess;
  if (split) {
    unchecked->g.setZero(n);
    unchecked->H.setZero(n, n);
  }
  if (per_term) per_term->clear();
  if (term_ms) term_ms->resize(sys.terms.size(), 0.0);
  double E = 0;
  for (size_t i = 0; i < sys.terms.size(); ++i) {
    SystemTerm& t = sys.terms[i];
    if (!t.active) {
      if (per_term) per_term->push_back(0.0);
      continue;
    }
    Timer timer;
    const bool apart = split && !t.term->in_nonlinearity_check();
    const double e = evaluate_term(t, q, apart ? &unchecked->g : grad, apart ? &unchecked->H : hess,
                                   sys.scratch_grad, sys.scratch_hess);
    if (term_ms) (*term_ms)[i] += timer.ms();
    if (per_term) per_term->push_back(e);
    E += e;
  }
  if (split) {
    *grad += unchecked->g;
    *hess += unchecked->H;
  }
  return E;
}

}  // namespace

double total_energy(StepSystem& sys, const std::vector<Configuration>& q, VecX* grad, MatX* hess,
                    std::vector<double>* per_term, std::vector<double>* term_ms) {
  return assemble(sys, q, grad, hess, per_term, term_ms, nullptr);
}

namespace {

/// The Newton direction δ = −H⁻¹ g: the sparse solver when chosen (it shifts H
/// itself when H does not factor), else the dense Cholesky with the
/// regularization shift (solve_in_place). Counts into rep.ms_solve.
void newton_direction(StepSystem& sys, MatX& H, const VecX& g, const NewtonOptions& o, VecX& delta, StepReport& rep) {
  Timer ts;
  bool solved = false;
  if (o.linear_solver == LinearSolver::Sparse) {
    if (!sys.sparse_solver)
      sys.sparse_solver = o.sparse_always ? std::make_shared<SparseHessianSolver>(1.0, 0.0)
                                          : std::make_shared<SparseHessianSolver>();
    solved = sys.sparse_solver->solve(H, g, delta);
    if (solved) rep.regularization = 0.0, ++rep.sparse_solves;
  }
  if (!solved) solve_in_place(H, g, o.regularization, delta, &rep.regularization);
  rep.ms_solve += ts.ms();
}

/// A Newton step limited by the caps (sim/step_cap.hpp): the step taken is
/// alpha·delta. Either cap counts the step as damped.
struct CappedStep {
  double alpha = 1.0;
  double slope = 0;            ///< Armijo's slope along delta
  bool bones_capped = false;   ///< delta is the per-bone capped step
  VecX whole;                  ///< bones_capped: the uncapped direction, to fall back to
  double whole_alpha = 1.0;    ///< bones_capped: the scale that caps `whole` as a whole
};

/// Leaf bones over the rotation cap are capped alone (the handle cap still
/// scales the whole step). If an inner bone is over it, the whole step is
/// scaled to the caps. `slope` = gᵀδ of the uncapped direction.
CappedStep cap_step(const StepSystem& sys, const std::vector<Configuration>& q, const VecX& g, double slope,
                    VecX& delta, const NewtonOptions& o) {
  CappedStep c;
  c.slope = slope;
  if (o.max_rotation_step > 0 && rotation_step_scale(delta, sys.bodies, o.max_rotation_step) < 1.0 &&
      rotation_cap_per_bone_applies(delta, sys.bodies, body_parents(sys), o.max_rotation_step)) {
    c.whole = delta;
    c.whole_alpha = std::min(handle_step_scale(delta, sys.bodies, o.max_z_step),
                             rotation_step_scale(delta, sys.bodies, o.max_rotation_step));
    cap_bone_rotations(delta, q, sys.bodies, o.max_rotation_step);
    c.alpha = handle_step_scale(delta, sys.bodies, o.max_z_step);
    // Armijo's slope along the capped direction; one that does not descend may not raise E.
    c.slope = std::min(0.0, g.dot(delta));
    c.bones_capped = true;
  } else {
    c.alpha = std::min(handle_step_scale(delta, sys.bodies, o.max_z_step),
                       rotation_step_scale(delta, sys.bodies, o.max_rotation_step));
  }
  return c;
}

/// What the trial evaluations leave for the step's report.
struct TrialRecord {
  VecX g_final;                 ///< the gradient at the final configuration (when final_valid)
  std::vector<double> per_term, term_ms;
  bool final_valid = false;     ///< g_final/per_term hold the final configuration's values
};

/// Halves c.alpha from the capped step until the trial is admissible (with
/// `line_search`: and lowers the energy by Armijo's rule), at most kMaxHalvings
/// times; when the per-bone capped step fails, falls back once to the whole
/// step scaled to the caps. Returns whether a trial was found (`trial`, `E_trial`).
/// On the `last` iteration the trial evaluation doubles as the final report's.
bool search_step(StepSystem& sys, const std::vector<Configuration>& q, VecX& delta, CappedStep& c, double E0,
                 double slope, bool line_search, bool last, TrialRecord& rec, std::vector<Configuration>& trial,
                 double& E_trial) {
  for (int halving = 0; halving <= kMaxHalvings; ++halving, c.alpha *= 0.5) {
    trial = retract_all(q, c.alpha * delta, sys.bodies);
    const double E1 = total_energy(sys, trial, last ? &rec.g_final : nullptr, nullptr, &rec.per_term, &rec.term_ms);
    rec.final_valid = last;
    const bool admissible = std::isfinite(E1);
    if (line_search ? (admissible && E1 <= E0 + kArmijo * c.alpha * c.slope) : admissible) {
      E_trial = E1;
      return true;
    }
    if (c.bones_capped && c.whole.size() > 0) {  // fall back to the whole step scaled to the caps
      delta = std::move(c.whole);
      c.whole.resize(0);
      c.alpha = 2.0 * c.whole_alpha;  // halved by the loop's increment
      c.slope = slope;
      c.bones_capped = false;
      --halving;
    }
  }
  return false;
}

/// The step's final figures: energy and gradient norm after it (report_final;
/// evaluated unless the last trial already did) and each term's energy and time.
void finish_report(StepSystem& sys, const std::vector<Configuration>& q, const NewtonOptions& o, TrialRecord& rec,
                   StepReport& rep) {
  rep.energy_after = rep.grad_norm_after = std::numeric_limits<double>::quiet_NaN();
  const size_t T = sys.terms.size();
  if (rec.term_ms.size() < T) rec.term_ms.resize(T, 0.0);
  if (o.report_final) {
    if (!rec.final_valid) {
      Timer ta;
      total_energy(sys, q, &rec.g_final, nullptr, &rec.per_term, &rec.term_ms);
      rep.ms_assemble += ta.ms();
    }
    rep.energy_after = 0;
    for (double e : rec.per_term) rep.energy_after += e;
    rep.grad_norm_after = rec.g_final.norm();
    for (size_t i = 0; i < T; ++i)
      rep.energies.push_back({sys.terms[i].term->name(), rec.per_term[i], rec.term_ms[i], sys.terms[i].active});
  } else {
    for (size_t i = 0; i < T; ++i)
      rep.energies.push_back({sys.terms[i].term->name(), std::numeric_limits<double>::quiet_NaN(), rec.term_ms[i],
                              sys.terms[i].active});
  }
}

void check_newton_options(const NewtonOptions& o) {
  require(o.iterations >= 1, "NewtonOptions::iterations = ", o.iterations, ", expected >= 1");
  require(o.iterations_after_damping >= 0, "NewtonOptions::iterations_after_damping = ", o.iterations_after_damping,
          ", expected >= 0");
  require(!o.nonlinearity_tolerance || (*o.nonlinearity_tolerance >= 0 && std::isfinite(*o.nonlinearity_tolerance)),
          "NewtonOptions::nonlinearity_tolerance = ", o.nonlinearity_tolerance.value_or(0),
          ", expected finite and >= 0 (or unset: automatic)");
}

}  // namespace

StepReport newton_minimize(StepSystem& sys, std::vector<Configuration>& q, const NewtonOptions& o) {
  check_newton_options(o);
  require(q.size() == sys.bodies.size(), "newton_minimize: ", q.size(), " configurations for ", sys.bodies.size(),
          " bodies");
  Timer total;
  StepReport rep;
  VecX g, delta;
  MatX H;
  TrialRecord rec;
  const double nonlinearity_tolerance = o.nonlinearity_tolerance.value_or(
      only_soft_dofs(sys) ? kAutoNonlinearityTolerance : 0.0);
  bool any_unchecked = false;
  for (const SystemTerm& t : sys.terms) any_unchecked |= t.active && !t.term->in_nonlinearity_check();
  UncheckedPart unchecked;
  std::vector<double> per_term0;
  int planned = o.iterations;  // grows while the last iteration is damped (iterations_after_damping)
  for (int it = 0; it < planned; ++it) {
    Timer ta;
    // The nonlinearity check may follow this iteration: keep the unchecked terms' part apart.
    const bool split = any_unchecked && nonlinearity_tolerance > 0 && it + 1 == planned && it < o.iterations;
    const double E0 = assemble(sys, q, &g, &H, split ? &per_term0 : nullptr, &rec.term_ms, split ? &unchecked : nullptr);
    rep.ms_assemble += ta.ms();
    require(std::isfinite(E0) && g.allFinite(), "newton_minimize: energy or gradient is not finite at the start of "
            "iteration ", it, " (E = ", E0, "); the configuration is inadmissible");
    const double gnorm = g.norm();
    if (it == 0) {
      rep.energy_before = E0;
      rep.grad_norm_before = gnorm;
    }
    if (o.gradient_tolerance > 0 && gnorm <= o.gradient_tolerance) break;
    ++rep.iterations;

    newton_direction(sys, H, g, o, delta, rep);
    const double slope = g.dot(delta);  // = −δᵀ(H + shift)δ < 0
    if (it == 0) rep.newton_decrement = std::sqrt(std::max(0.0, -slope));

    Timer tl;
    CappedStep c = cap_step(sys, q, g, slope, delta, o);
    std::vector<Configuration> trial;
    double E_trial = E0;
    // An iteration added after a damped one must lower the step's objective (Armijo):
    // without that, on targets jumping ~3 rad (builtin:torture) the added iterations
    // carried the bones through in one step and crushed the flesh they drag.
    const bool added = it >= o.iterations;
    const bool last = it + 1 == planned && o.report_final;
    const bool ok = search_step(sys, q, delta, c, E0, slope, o.line_search || added, last, rec, trial, E_trial);
    rep.ms_assemble += tl.ms();
    // Converged to round-off: the line search found no decrease, but the
    // predicted one is below what the energy resolves. The iterate is the
    // minimum (e.g. a held grasp at rest); keep it and stop, not a rejection.
    if (!ok && o.line_search && -slope <= 1e-12 * std::max(1.0, std::abs(E0))) {
      rec.final_valid = false;
      break;
    }
    // An added iteration that finds no decrease ends the step where the planned ones left it.
    if (!ok && added) {
      rec.final_valid = false;
      break;
    }
    StepOutcome outcome;
    if (!ok) {
      rec.final_valid = false;
      outcome = StepOutcome::Rejected;
      ++rep.rejected;
      rep.step_scale = 0;
    } else {
      q = std::move(trial);
      rep.step_scale = c.alpha;
      const bool full = c.alpha == 1.0 && !c.bones_capped;  // whole_alpha < 1 when the fallback ran
      outcome = full ? StepOutcome::Accepted : StepOutcome::Damped;
      (full ? rep.accepted : rep.damped)++;
    }
    if (int(outcome) > int(rep.outcome)) rep.outcome = outcome;
    if (!ok) break;
    if (outcome == StepOutcome::Damped && it + 1 == planned && planned < o.iterations + o.iterations_after_damping) {
      ++planned;
      ++rep.iterations_after_damping;
    } else if (outcome == StepOutcome::Accepted && it + 1 == planned && !added && nonlinearity_tolerance > 0 &&
               -slope > 1e-12 * std::max(1.0, std::abs(E0))) {
      // The full Newton step predicts a decrease of ½ δᵀHδ = −½ gᵀδ. With
      // contact terms (left out of the check), the other terms' change is
      // compared with their own model, −g_cᵀδ − ½ δᵀH_cδ (g_c = g − g_u,
      // H_c = H − H_u, δᵀHδ = −gᵀδ), still as a share of the whole step's
      // predicted decrease.
      const double predicted = -0.5 * slope;
      double departure = (E0 - E_trial) - predicted;
      if (split) {
        const VecX& d = delta;
        const double predicted_checked = predicted + unchecked.g.dot(d) + 0.5 * d.dot(unchecked.H * d);
        const double actual_checked = (E0 - unchecked_energy(sys, per_term0)) - (E_trial - unchecked_energy(sys, rec.per_term));
        departure = actual_checked - predicted_checked;
      }
      if (std::abs(departure / predicted) > nonlinearity_tolerance) {
        ++planned;
        ++rep.iterations_for_nonlinearity;
      }
    }
  }
  finish_report(sys, q, o, rec, rep);
  rep.ms_total = total.ms();
  return rep;
}

StepReport newton_minimize(const std::vector<EnergyTerm*>& terms, const StepContext& ctx, Configuration& q,
                           const NewtonOptions& options) {
  std::vector<StepContext> contexts(terms.size(), ctx);
  std::vector<std::unique_ptr<TermCache>> caches;
  StepSystem sys;
  sys.bodies = {ctx.layout};
  sys.size = ctx.layout.end();
  const TermPlacement whole = TermPlacement::from_ranges({{ctx.layout.base, ctx.layout.size()}});
  for (size_t i = 0; i < terms.size(); ++i) {
    StepContext& c = contexts[i];
    c.bound = {BoundBody{0, 0, ctx.avatar, ctx.layout, nullptr, &ctx.q_prev, &ctx.q_prev2}};
    caches.push_back(begin_term_step(*terms[i], c));
    sys.terms.push_back({terms[i], &c, whole, terms[i]->active(c)});
  }
  std::vector<Configuration> qs{q};
  StepReport rep = newton_minimize(sys, qs, options);
  q = std::move(qs[0]);
  return rep;
}

}  // namespace sflsh
