#pragma once
// Internals of the bounded biharmonic weights (include/sflsh/basis/bounded_biharmonic.hpp):
//   bbw_inactive_set.cpp  — the inactive-set systems of one column, factored once and
//                           updated by bordering,
//   bbw_active_set.cpp    — one column's bound-constrained QP by the primal–dual
//                           active-set method, and its KKT residual,
//   bounded_biharmonic.cpp — the QPs of all columns (in parallel), the weights, the report.
#include <vector>

#include "basis/cholmod_llt.hpp"
#include "sflsh/basis/bounded_biharmonic.hpp"
#include "sflsh/core/types.hpp"

namespace sflsh::basis::bbw_internal {

using SpMat = Eigen::SparseMatrix<double>;

/// Node states of the active-set method: free (inactive), at a bound, or
/// outside the column's support (held at 0, not a bound: never released and
/// not part of the KKT test).
enum : char { kFree = 0, kLower = 1, kUpper = 2, kOutside = 3 };

/// Dimensionless KKT residual of x for min ½xᵀAx + qᵀx, 0 ≤ x ≤ 1 with
/// gradient g = Ax + q (see BbwReport::kkt_residual).
/// Nodes marked in `outside` (when non-null) are held values, not bounds: skipped.
double kkt_residual(const VecX& x, const VecX& g, double qnorm, const std::vector<char>* outside = nullptr);

struct ColumnResult {
  VecX x;
  std::vector<double> history;
  int iterations = 0;
  int max_inactive = 0;
  int factorizations = 0;
};

/// Solves the inactive-set systems Q_II x_I = −q_I − Q_IA x_A of one column's
/// active-set iterations. A fresh factorization per iteration dominated the
/// cost, while most iterations move only a few nodes at the support boundary;
/// so this keeps the CHOLMOD factor F of Q over a base set I0 and treats the
/// difference to the current set I as a bordered system (Schur complement,
/// i.e. a capacitance-matrix / Sherman–Morrison–Woodbury update; Hager 1989,
/// "Updating the inverse of a matrix"): nodes of I \ I0 are extra rows and
/// columns of Q, nodes of I0 \ I are held at their bound by Lagrange
/// multipliers. The columns F⁻¹B of the border are cached per node, so a
/// node that toggles back and forth costs one solve. When the cache would
/// exceed `max_border` columns, I becomes the new base and is refactored.
class InactiveSetSolver {
 public:
  InactiveSetSolver(const SpMat& A, int max_border) : A_(A), max_border_(max_border) {
    base_index_.assign(size_t(A.rows()), -1);
    cache_col_.assign(size_t(A.rows()), -1);
  }
  int factorizations() const { return factorizations_; }

  /// Overwrites x on the free nodes of `state` (others hold their bound value).
  void solve(const std::vector<char>& state, const VecX& q, VecX& x);

 private:
  /// Makes the free nodes of `state` the new base set and factors Q over it.
  void refactor(const std::vector<char>& state, int num_free);

  const SpMat& A_;
  const int max_border_;
  detail::CholmodLLT llt_;
  bool factored_ = false;
  int factorizations_ = 0;
  std::vector<int> base_, base_index_;  // I0 and its inverse (−1 outside)
  std::vector<int> cache_col_;          // column of Z_ caching F⁻¹B e_j, or −1
  int cache_cols_ = 0;
  MatX Z_;
};

/// One bound-constrained QP  min ½xᵀAx + qᵀx, 0 ≤ x ≤ 1, by the primal–dual
/// active-set method. `dist` (#free): distance (m) of each node to the fixed
/// nodes with nonzero value; nodes farther than `radius` start at the lower
/// bound (see BbwOptions::initial_radius_factor). Nodes marked in `outside`
/// (#free, when non-null) lie outside the column's support: held at 0.
ColumnResult solve_column(const SpMat& A, const VecX& q, const VecX& dist, double radius, const BbwOptions& opt,
                          int column, const std::vector<char>* outside = nullptr);

}  // namespace sflsh::basis::bbw_internal
