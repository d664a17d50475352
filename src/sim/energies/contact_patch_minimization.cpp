// The patch's displacement δu minimized at the body's configuration:
// Newton on δu with q fixed, warm-started from the last linearization
// (contact_patch.hpp, "Condensation").
#include <cmath>
#include <limits>

#include "sflsh/sim/energies/contact_patch.hpp"
#include "sim/energies/contact_patch_cache.hpp"

namespace sflsh {

using contact_patch_detail::local_layout;
using contact_patch_detail::patch_cache;
using contact_patch_detail::PatchCache;
using contact_patch_detail::PatchCholesky;

namespace {
bool same_configuration(const Configuration& a, const Configuration& b) {
  if (a.z.size() != b.z.size() || a.bones.size() != b.bones.size() || a.z != b.z) return false;
  for (size_t j = 0; j < a.bones.size(); ++j)
    if (a.bones[j].matrix() != b.bones[j].matrix()) return false;
  return true;
}
}  // namespace

Isometry ContactPatchTerm::object_pose(const StepContext& ctx) const {
  return dynamic_ ? ctx.bound[1].q->bones[0] : Isometry::Identity();
}

bool ContactPatchTerm::at_configuration(const StepContext& ctx, const Configuration& q, const Configuration& seen,
                                        const Isometry& object_seen) const {
  return same_configuration(q, seen) && object_pose(ctx).matrix() == object_seen.matrix();
}

bool ContactPatchTerm::patch_solved_at(const StepContext& ctx, const Configuration& q) const {
  const PatchCache& c = patch_cache(ctx, name());
  return c.solved && at_configuration(ctx, q, c.q_solved, c.object_solved);
}

VecX ContactPatchTerm::move_between(const StepContext& ctx, const Configuration& q, const Configuration& q_from,
                                    const Configuration* object, const Configuration* object_from) const {
  const PatchCache& c = patch_cache(ctx, name());
  const DofLayout& L = local_layout(ctx);
  VecX dq = VecX::Zero(c.Hqp.rows());
  dq.head(L.end()) += tangent_between(q, q_from, L);
  if (dynamic_) {
    const DofLayout& O = ctx.bound[1].layout;
    dq.head(O.end()) += tangent_between(*object, *object_from, O);
  }
  return dq;
}

VecX ContactPatchTerm::linearized_patch(const StepContext& ctx, const Configuration& q) const {
  const PatchCache& c = patch_cache(ctx, name());
  const Configuration* object = dynamic_ ? ctx.bound[1].q : nullptr;
  return c.du_lin - c.linear_response(move_between(ctx, q, c.q_lin, object, &c.object_lin));
}

VecX ContactPatchTerm::step_patch(const StepContext& ctx, const Configuration& q) const {
  const PatchCache& c = patch_cache(ctx, name());
  if (c.du.size() == 0 || c.releasing || !c.linearized || patch_solved_at(ctx, q)) return minimize_patch(ctx, q);
  VecX du = linearized_patch(ctx, q);
  // Where it would crush a patch tet (Φ = +inf), the minimizer instead.
  for (double det : patch_tet_determinants(c, q.z, du))
    if (!(det > 0)) return minimize_patch(ctx, q);
  return du;
}

VecX ContactPatchTerm::minimize_patch(const StepContext& ctx, const Configuration& q, Evaluation* start,
                                      bool* at_start) const {
  PatchCache& c = patch_cache(ctx, name());
  if (at_start) *at_start = false;
  if (c.du.size() == 0 || c.releasing) return c.du;  // released: δu prescribed (begin_step)
  // The integrator evaluates the final configuration several times (trial,
  // report): the minimizer is kept.
  if (patch_solved_at(ctx, q)) return c.du;
  const Isometry object = object_pose(ctx);
  // The step's first start: δu extrapolated from its last two steps (a dent
  // that deepens keeps deepening); then the last linearization's
  // back-substitution of the bordered Newton system.
  VecX du = !c.solved && c.du_predicted.size() == c.du.size() ? c.du_predicted : c.du;
  if (c.linearized) du = linearized_patch(ctx, q);
  Evaluation &ev = c.inner, &trial = c.inner_trial;
  ++c.minimizations;
  EvaluationMode exact, energy_only;
  exact.project = false;
  exact.subspace_energy = false;
  energy_only.p_derivatives = false;
  energy_only.subspace_energy = false;
  // A Newton iteration's start (`start`) needs the evaluation at the minimizer
  // with q's derivatives and the projected Φ_pp. When the warm start is likely
  // a minimizer (every patch node was in the last step's patch) it is
  // evaluated so first: when its Newton step with that Φ_pp moves no node by
  // more than the tolerance, it is the minimizer, and `*start` and
  // c.start_llt (Φ_pp's factor) hold what the iteration needs. Otherwise the
  // Newton iteration below runs.
  if (start && c.settled) {
    EvaluationMode full;
    full.q_derivatives = full.q_hessian = true;
    const double E = evaluate_patch(ctx, q, du, full, *start);
    if (std::isfinite(E) && c.start_llt.factor(c.pattern, start->Hpp) &&
        (start->gp.norm() < 1e-12 || c.start_llt.solve(start->gp).cwiseAbs().maxCoeff() <= options_.inner_tolerance)) {
      c.du = du;
      c.solved = true;
      c.q_solved = q;
      c.object_solved = object;
      *at_start = true;
      return du;
    }
  }
  // Newton on δu: the exact element Hessians (quadratic convergence) unless
  // compression makes them indefinite, then their PSD majorizers; Armijo
  // backtracking; stops when the Newton step s moves no node by more than
  // inner_tolerance (or the gradient vanishes).
  // The start: the lower energy of the warm start and the last minimizer (a
  // warm start predicted past a tet's collapse starts the Newton iteration
  // far up the compression barrier, where it gains only a constant factor
  // of the energy per iteration), else no patch displacement; if every start
  // is inadmissible the term's energy is +inf there and the step backtracks.
  // The warm start, which usually starts the iteration, is evaluated with its
  // derivatives; the last minimizer for its energy alone. A full step's trial
  // is evaluated with its derivatives: accepted, it starts the next iteration
  // (Armijo's check and the next Newton step share one evaluation).
  double E0 = evaluate_patch(ctx, q, du, exact, ev);
  bool evaluated = std::isfinite(E0);  // `ev` holds the evaluation at du
  if (c.du.size() == du.size() && c.du != du) {
    const double E_last = evaluate_patch(ctx, q, c.du, energy_only, trial);
    if (E_last < E0 || !std::isfinite(E0)) du = c.du, E0 = E_last, evaluated = false;
  }
  if (!std::isfinite(E0)) du.setZero(), evaluated = false;
  for (int it = 0; it < options_.max_inner_iterations; ++it) {
    if (!evaluated) E0 = evaluate_patch(ctx, q, du, exact, ev);
    evaluated = false;
    if (!std::isfinite(E0)) break;
    if (ev.gp.norm() < 1e-12) break;
    PatchCholesky& llt = c.inner_llt;
    require(ev.has_Hpp, name(), ": the inner Newton step needs the evaluation's Φ_pp");
    if (!llt.factor(c.pattern, ev.Hpp)) {
      EvaluationMode projected = exact;
      projected.project = true;
      evaluate_patch(ctx, q, du, projected, ev);
      if (!llt.factor(c.pattern, ev.Hpp)) {
        // PSD by construction and PD with mass: only a degenerate tet gets here.
        ev.Hpp.diagonal() *= 1.0 + 1e-8;
        require(llt.factor(c.pattern, ev.Hpp), name(), ": the patch's Hessian is not positive definite");
      }
    }
    const VecX step = llt.solve(-ev.gp);
    if (step.cwiseAbs().maxCoeff() <= options_.inner_tolerance) break;
    const double slope = ev.gp.dot(step);
    double alpha = 1, E1 = E0;
    bool ok = false;
    for (int halving = 0; halving < 30; ++halving, alpha *= 0.5) {
      E1 = evaluate_patch(ctx, q, du + alpha * step, halving == 0 ? exact : energy_only, trial);
      if (std::isfinite(E1) && E1 <= E0 + 1e-4 * alpha * slope + 1e-15 * std::abs(E0)) {
        ok = true;
        break;
      }
    }
    if (!ok) break;
    du += alpha * step;
    ++c.inner_iterations;
    if (alpha * step.cwiseAbs().maxCoeff() < 1e-13) break;
    if (alpha == 1.0) {
      std::swap(ev, trial);
      E0 = E1;
      evaluated = true;
    }
  }
  c.du = du;
  c.solved = true;
  c.q_solved = q;
  c.object_solved = object;
  return du;
}

}  // namespace sflsh
