// One column of the bounded biharmonic weights: the bound-constrained QP by the
// primal–dual active-set method, and its KKT residual.
#include <algorithm>
#include <cmath>
#include <limits>

#include "basis/bbw_internal.hpp"
#include "sflsh/core/error.hpp"

namespace sflsh::basis::bbw_internal {

double kkt_residual(const VecX& x, const VecX& g, double qnorm, const std::vector<char>* outside) {
  double r = 0.0;
  for (Eigen::Index i = 0; i < x.size(); ++i) {
    if (outside && (*outside)[size_t(i)]) continue;
    const double viol = std::max({0.0, -x(i), x(i) - 1.0});
    double pg;
    if (x(i) <= 0.0) pg = std::max(0.0, -g(i));
    else if (x(i) >= 1.0) pg = std::max(0.0, g(i));
    else pg = std::abs(g(i));
    r = std::max({r, viol, pg / qnorm});
  }
  return r;
}

/// One bound-constrained QP  min ½xᵀAx + qᵀx, 0 ≤ x ≤ 1, by the primal–dual
/// active-set method. `dist` (#free): distance (m) of each node to the fixed
/// nodes with nonzero value; nodes farther than `radius` start at the lower
/// bound (see BbwOptions::initial_radius_factor). Nodes marked in `outside`
/// (#free, when non-null) lie outside the column's support: held at 0.
ColumnResult solve_column(const SpMat& A, const VecX& q, const VecX& dist, double radius, const BbwOptions& opt,
                          int column, const std::vector<char>* outside) {
  const int n = int(A.rows());
  const double qnorm = std::max(q.lpNorm<Eigen::Infinity>(), std::numeric_limits<double>::min());
  const double mtol = opt.multiplier_tolerance * qnorm;
  ColumnResult res;
  res.x = VecX::Zero(n);
  std::vector<char> state(n);
  for (int i = 0; i < n; ++i) state[i] = outside && (*outside)[i] ? kOutside : dist(i) <= radius ? kFree : kLower;
  std::vector<int> released(n, 0);  // releases in the conservative phase, see below
  std::vector<char> frozen(n, 0);

  InactiveSetSolver solver(A, opt.max_border_columns);
  VecX& x = res.x;
  for (int it = 1; it <= opt.max_iterations; ++it) {
    int num_free = 0;
    for (int i = 0; i < n; ++i) {
      if (state[i] != kFree) x(i) = state[i] == kUpper ? 1.0 : 0.0;
      num_free += state[i] == kFree;
    }
    if (num_free > 0) solver.solve(state, q, x);
    res.max_inactive = std::max(res.max_inactive, num_free);
    const VecX g = A * x + q;  // multipliers on the active set
    res.history.push_back(kkt_residual(x, g, qnorm, outside));
    res.iterations = it;
    res.factorizations = solver.factorizations();

    // Active-set update. Plain PDAS first; after opt.pdas_iterations add-only,
    // or release-only when nothing is violated. A node bound again after
    // opt.max_releases such releases stays bound ("frozen"): every node is
    // then released finitely often, so the iteration ends (add/release alone
    // can cycle on long, thin supports, seen with free bones), and the KKT
    // residual reports what freezing cost.
    const bool conservative = it > opt.pdas_iterations;
    bool primal_violation = false;
    for (int i = 0; i < n; ++i)
      if (state[i] == kFree && (x(i) < 0.0 || x(i) > 1.0)) primal_violation = true;
    bool changed = false;
    for (int i = 0; i < n; ++i) {
      if (state[i] == kFree) {
        if (x(i) < 0.0) state[i] = kLower, changed = true;
        else if (x(i) > 1.0) state[i] = kUpper, changed = true;
        if (state[i] != kFree && released[i] >= opt.max_releases) frozen[i] = 1;
      } else if (state[i] != kOutside && !(conservative && (primal_violation || frozen[i]))) {
        if ((state[i] == kLower && g(i) < -mtol) || (state[i] == kUpper && g(i) > mtol)) {
          state[i] = kFree;
          if (conservative) ++released[i];
          changed = true;
        }
      }
    }
    // Settled, or converged to within kkt_tolerance while nodes at the C¹
    // support boundary still toggle at round-off level (seen with free bones).
    if (!changed || res.history.back() <= opt.kkt_tolerance) {
      x = x.cwiseMax(0.0).cwiseMin(1.0);  // round-off on the inactive set
      return res;
    }
  }
  fail("bounded biharmonic weights: active-set iteration for column ", column, " did not settle in ",
       opt.max_iterations, " iterations (KKT residual ", res.history.back(), ")");
}

}  // namespace sflsh::basis::bbw_internal
