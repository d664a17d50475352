#include "sflsh/sim/sparse_hessian_solve.hpp"

#include <vector>

namespace sflsh {

namespace {

/// H_ij as the solve sees it: a zero diagonal entry reads as 1 (decoupled DoF).
double entry(const MatX& H, Eigen::Index i, Eigen::Index j) {
  const double v = H(i, j);
  return i == j && v == 0.0 ? 1.0 : v;
}

}  // namespace

bool SparseHessianSolver::fill(const MatX& H) {
  const Eigen::Index n = H.rows();
  if (A_.rows() != n) return false;
  double* values = A_.valuePtr();
  const int* outer = A_.outerIndexPtr();
  const int* inner = A_.innerIndexPtr();
  for (Eigen::Index j = 0; j < n; ++j) {
    int p = outer[j];
    const int end = outer[j + 1];
    for (Eigen::Index i = j; i < n; ++i) {
      if (p < end && inner[p] == i) {
        values[p++] = entry(H, i, j);
      } else if (H(i, j) != 0.0) {
        return false;
      }
    }
  }
  return true;
}

void SparseHessianSolver::widen(const MatX& H) {
  const Eigen::Index n = H.rows();
  const bool had = A_.rows() == n;
  if (had) A_.coeffs().setOnes();  // membership below, whatever the last values were
  std::vector<Eigen::Triplet<double>> trip;
  for (Eigen::Index j = 0; j < n; ++j)
    for (Eigen::Index i = j; i < n; ++i)
      if (i == j || H(i, j) != 0.0 || (had && A_.coeff(i, j) != 0.0)) trip.emplace_back(int(i), int(j), 1.0);
  A_.resize(n, n);
  A_.setFromTriplets(trip.begin(), trip.end());
  A_.makeCompressed();
  ldlt_.analyzePattern(A_);
  ++analyses_;
  factor_flops_ = 0;
  for (Eigen::Index j = 0; j < ldlt_.column_counts().size(); ++j)
    factor_flops_ += double(ldlt_.column_counts()[j]) * double(ldlt_.column_counts()[j]);
}

bool SparseHessianSolver::solve(const MatX& H, const VecX& g, VecX& delta) {
  const Eigen::Index n = H.rows();
  if (!fill(H)) {
    widen(H);
    fill(H);
  }
  if (double(A_.nonZeros()) > max_density_ * 0.5 * double(n) * double(n + 1)) return false;
  if (simplicial_slowdown_ * factor_flops_ > double(n) * double(n) * double(n) / 3.0) return false;
  ldlt_.factorize(A_);
  if (ldlt_.info() != Eigen::Success || !(ldlt_.vectorD().minCoeff() > 0.0)) return false;
  delta = ldlt_.solve(-g);
  return delta.allFinite();
}

}  // namespace sflsh
