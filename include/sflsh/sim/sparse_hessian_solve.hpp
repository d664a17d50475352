#pragma once
// The Newton system H δ = −g solved by a sparse LDLᵀ factorization (Eigen's
// SimplicialLDLT, AMD ordering) of H's nonzero pattern. With compactly
// supported handle weights, a handle couples only to the handles whose
// supports overlap its own at some cubature sample and to the bones whose
// skinning reaches them, so H (bones and soft DoFs) is sparse and its pattern
// is the same every step: it is analysed once (symbolic factorization) and
// only refactored numerically afterwards.
//
// The terms still assemble the dense H (EnergyTerm's interface: dense local
// blocks, which a term such as a contact patch's Schur complement fills
// densely). Each solve reads H's lower triangle against the stored pattern;
// an entry outside it (a term that was inactive until now, a new contact
// block) widens the pattern to the union and analyses it again. A pattern
// not worth a sparse factorization is declined (solve() returns false and
// the caller factors H densely): one denser than `max_density`, or one whose
// factorization, by the symbolic analysis' column counts c_j of L, costs
// Σ_j c_j² multiply-adds more than 1/`simplicial_slowdown` of the dense
// Cholesky's n³/3 (a simplicial factorization works column by column,
// without the dense one's blocked, vectorized kernels).
#include <Eigen/Sparse>
#include <Eigen/SparseCholesky>

#include "sflsh/core/types.hpp"

namespace sflsh {

class SparseHessianSolver {
 public:
  explicit SparseHessianSolver(double max_density = 0.3, double simplicial_slowdown = 4.0)
      : max_density_(max_density), simplicial_slowdown_(simplicial_slowdown) {}
  /// δ = −H⁻¹ g from H's lower triangle (H symmetric; a zero diagonal entry
  /// counts as 1, as in the dense solve: its DoF is decoupled). Returns false,
  /// leaving δ unspecified, when the pattern is too dense or H is not positive
  /// definite (a pivot ≤ 0): the caller then takes the dense path.
  bool solve(const MatX& H, const VecX& g, VecX& delta);
  /// Stored entries of the lower triangle (diagonal included) of the pattern.
  long pattern_nonzeros() const { return A_.nonZeros(); }
  /// Symbolic analyses so far (1 when the pattern never changed).
  int analyses() const { return analyses_; }
  /// Multiply-adds of one numeric factorization of the analysed pattern, Σ_j c_j².
  double factor_flops() const { return factor_flops_; }

 private:
  /// Copies H's lower triangle onto the pattern; false if H has an entry outside it.
  bool fill(const MatX& H);
  /// Sets the pattern to the union of the current one and H's lower-triangle nonzeros.
  void widen(const MatX& H);

  /// Eigen's LDLᵀ with the symbolic column counts of L exposed.
  struct LDLT : Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>, Eigen::Lower, Eigen::AMDOrdering<int>> {
    const Eigen::VectorXi& column_counts() const { return m_nonZerosPerCol; }
  };

  double max_density_, simplicial_slowdown_;
  Eigen::SparseMatrix<double> A_;  ///< lower triangle, column-major
  LDLT ldlt_;
  int analyses_ = 0;
  double factor_flops_ = 0;
};

}  // namespace sflsh
