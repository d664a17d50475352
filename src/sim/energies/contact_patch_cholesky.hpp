#pragma once
// Private to contact_patch*.cpp: the sparse Cholesky factor of the patch
// block Φ_pp (and of the guard's Φ_pp ∓ K0_pp), which the evaluation
// assembles densely. The block couples only nodes that share a patch tet or a
// touching face: the factor of a 76-node patch (228 DoFs) holds ~10 % of the
// dense one's entries and its factorization costs about a quarter of it.
#include <memory>

#include "sflsh/core/types.hpp"

namespace sflsh::contact_patch_detail {

class PatchCholesky {
 public:
  PatchCholesky();
  ~PatchCholesky();
  /// A copy factors the copied values again (the same factor, bit for bit).
  PatchCholesky(const PatchCholesky& other);
  PatchCholesky& operator=(const PatchCholesky& other);
  PatchCholesky(PatchCholesky&&) noexcept;
  PatchCholesky& operator=(PatchCholesky&&) noexcept;

  /// Factors A + sign B + shift I (symmetric: the lower triangles of A and B
  /// are read; B may be null). The fill-reducing analysis is kept while the
  /// nonzeros stay within the pattern it was made for (a new nonzero widens
  /// the pattern and redoes it). False when the matrix is not positive definite.
  bool factor(const MatX& A, const MatX* B = nullptr, double sign = 0, double shift = 0);
  bool ok() const;
  /// The factored matrix's size (0 before the first successful factorization).
  long rows() const;
  /// M⁻¹ b for the factored matrix M.
  VecX solve(const VecX& b) const;
  /// X = L⁻¹ P C for M = Pᵀ L Lᵀ P: XᵀX = Cᵀ M⁻¹ C. X is row-major (its
  /// storage reused): the forward substitution updates whole rows, one vector
  /// operation per nonzero of L.
  void half_solve(const MatX& C, MatXr& X) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace sflsh::contact_patch_detail
