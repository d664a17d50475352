#pragma once
// Private to contact_patch*.cpp: the sparse Cholesky factor of the patch
// block Φ_pp (and of the guard's Φ_pp ∓ K0_pp), which the evaluation
// assembles densely. The block couples only nodes that share a patch tet or a
// touching face: the factor of a 76-node patch (228 DoFs) holds ~20 % of the
// dense one's entries. It is factored in 3x3 node blocks (3 DoFs per node).
#include <memory>

#include "sflsh/core/types.hpp"

namespace sflsh::contact_patch_detail {

/// The nonzero pattern and fill-reducing ordering that a patch's factors
/// share (one analysis when the patch grows, not one per factor). It widens
/// while the patch keeps its size and starts over when the size changes.
class PatchPattern {
 public:
  PatchPattern();
  ~PatchPattern();
  /// A copy is the same pattern under a new identity (its factors re-read it).
  PatchPattern(const PatchPattern& other);
  PatchPattern& operator=(const PatchPattern& other);
  PatchPattern(PatchPattern&&) noexcept;
  PatchPattern& operator=(PatchPattern&&) noexcept;
  /// Analyses since construction (a figure for tests and profiles).
  long analyses() const;

 private:
  friend class PatchCholesky;
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

class PatchCholesky {
 public:
  PatchCholesky();
  ~PatchCholesky();
  /// A copy holds the same factor (bit for bit) on a copy of its structure.
  PatchCholesky(const PatchCholesky& other);
  PatchCholesky& operator=(const PatchCholesky& other);
  PatchCholesky(PatchCholesky&&) noexcept;
  PatchCholesky& operator=(PatchCholesky&&) noexcept;

  /// Factors A + sign B + shift I (symmetric: the lower triangles of A and B
  /// are read; B may be null) on `pattern`, which this call analyses when the
  /// size changes and widens when a nonzero of A or B lies outside it. False
  /// when the matrix is not positive definite.
  bool factor(PatchPattern& pattern, const MatX& A, const MatX* B = nullptr, double sign = 0, double shift = 0);
  /// The same on a pattern of this factor's own.
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
