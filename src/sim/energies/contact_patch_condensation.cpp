// The term's evaluation for the step's Newton iteration: the patch
// minimized out (or, for a trial, stepped along the last linearization) and,
// with the Hessian, condensed into the body's system by the Schur complement
// Φ_qq − Φ_qp Φ_pp⁻¹ Φ_pq with its guard (contact_patch.hpp, "Condensation").
#include <cmath>
#include <vector>

#include "sflsh/core/error.hpp"
#include "sflsh/sim/energies/contact_patch.hpp"
#include "sim/energies/contact_patch_cache.hpp"

namespace sflsh {

using contact_patch_detail::local_layout;
using contact_patch_detail::patch_cache;
using contact_patch_detail::PatchCache;

double ContactPatchTerm::compute(const StepContext& ctx, const Configuration& q, VecRef* grad, MatRef* hess) const {
  // A Newton iteration's start (asked for the Hessian) minimizes the patch
  // out; its trials take δu from the bordered system (step_patch).
  PatchCache& c = patch_cache(ctx, name());
  // A trial's evaluation is kept for the report, which asks at the accepted one.
  Evaluation& ev = hess ? c.start : c.trial;
  bool evaluated = false;  // by minimize_patch, at a warm start that minimized Φ
  const VecX du = hess ? minimize_patch(ctx, q, &ev, &evaluated) : step_patch(ctx, q);
  EvaluationMode mode;
  mode.q_derivatives = grad || hess;
  mode.q_hessian = hess != nullptr;
  mode.p_derivatives = hess != nullptr;
  if (!hess) c.has_trial = false;
  const double E = evaluated ? ev.energy : evaluate_patch(ctx, q, du, mode, ev);
  if (!hess) {
    if (grad && std::isfinite(E)) *grad += ev.gq;
    c.trial_q = q;
    c.trial_object = object_pose(ctx);
    c.trial_du = du;
    c.has_trial = true;
    return E;
  }
  if (!std::isfinite(E)) return E;
  if (grad) *grad += ev.gq;
  for (int j : c.q_rows)  // Φ_qq is zero outside these rows and columns
    for (int i : c.q_rows) (*hess)(i, j) += ev.Hqq(i, j);
  if (du.size() == 0 || c.releasing) return E;  // a prescribed δu: no condensation
  // Schur complement over the rows of the layout the patch touches (Φ_qp is
  // column-major: its columns are scanned, and copied to C = Φ_pq's rows).
  std::vector<char>& touched = c.schur_row;
  touched.assign(size_t(ev.Hqp.rows()), 0);
  for (int j = 0; j < ev.Hqp.cols(); ++j)
    for (int r : c.q_rows)
      if (ev.Hqp(r, j) != 0) touched[size_t(r)] = 1;
  std::vector<int> rows;
  for (int r : c.q_rows)
    if (touched[size_t(r)]) rows.push_back(r);
  if (rows.empty()) return E;
  MatX& Hc = c.schur_C;
  Hc.resize(ev.Hqp.cols(), long(rows.size()));
  for (size_t k = 0; k < rows.size(); ++k) Hc.col(long(k)) = ev.Hqp.row(rows[k]).transpose();
  require(ev.has_Hpp, name(), ": the condensation needs the evaluation's Φ_pp");
  contact_patch_detail::PatchCholesky& llt = c.Hpp_llt;
  if (evaluated)
    std::swap(llt, c.start_llt);
  else
    llt.factor(c.pattern, ev.Hpp);
  require(llt.ok(), name(), ": the patch's Hessian is not positive definite");
  // The complement must stay below what the other terms carry for these DoFs
  // (Wᵀ K0 W over the patch tets, the nodes' inertia, the contact): by the
  // element-wise block argument it does when Φ_pp ⪰ K0_pp + M + C, i.e. when
  // the dented state is at least as stiff as the subspace's own (K1 ⪰ K0 over
  // the patch DoFs). When the patch relaxes a strained subspace state, K1 ≪ K0
  // and the complement can exceed the whole step's Hessian many times (no
  // diagonal shift makes it positive definite): Φ_pp + K0_pp is used instead,
  // which is ⪰ K0_pp + M + C because K1 is PSD-projected. Only the Hessian
  // changes; in the first case it is as before.
  contact_patch_detail::PatchCholesky &below = c.below_llt, &guarded = c.guarded_llt;
  const bool relaxed = !below.factor(c.pattern, ev.Hpp, &c.K0pp, -1.0, 1e-9 * ev.Hpp.diagonal().cwiseAbs().maxCoeff());
  require(!relaxed || guarded.factor(c.pattern, ev.Hpp, &c.K0pp, 1.0), name(), ": the patch's guarded Hessian is not positive definite");
  c.linearized = true;
  c.q_lin = q;
  if (dynamic_) c.object_lin = *ctx.bound[1].q;
  const VecX rest = llt.solve(ev.gp);  // Φ_pp⁻¹ Φ_p: what δu has left to its minimizer (inner_tolerance)
  c.du_lin = du - rest;
  // The bordered system's right-hand side: Φ_q − Φ_qp Φ_pp⁻¹ Φ_p (Φ_qp with the dented tets' own stiffness).
  if (grad) {
    const int z0 = local_layout(ctx).z_offset();
    for (int r : c.q_rows) {
      (*grad)[r] -= ev.Hqp.row(r).dot(rest);
      if (r >= z0 && r < z0 + ev.Hzp_stiffening.rows()) (*grad)[r] -= ev.Hzp_stiffening.row(r - z0).dot(rest);
    }
  }
  MatXr& X = c.schur_X;
  (relaxed ? guarded : llt).half_solve(Hc, X);
  MatX& S = c.schur_S;  // XᵀX, its lower half
  S.setZero(X.cols(), X.cols());
  S.selfadjointView<Eigen::Lower>().rankUpdate(X.transpose());
  for (size_t l = 0; l < rows.size(); ++l)  // down the step Hessian's columns
    for (size_t k = 0; k < rows.size(); ++k) (*hess)(rows[k], rows[l]) -= k >= l ? S(long(k), long(l)) : S(long(l), long(k));
  // Kept for the trials: Φ_pq with the dented tets' own stiffness (the complement takes K0's).
  c.Hqp.swap(ev.Hqp);  // the evaluation gets the last linearization's storage back
  c.Hzp_stiffening.swap(ev.Hzp_stiffening);
  c.z_lin = local_layout(ctx).z_offset();
  return E;
}

}  // namespace sflsh
