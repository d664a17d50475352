#pragma once
// Private to basis/: a minimal RAII wrapper of a CHOLMOD sparse Cholesky
// factorization (supernodal when it pays, AMD ordering) with dense
// multi-right-hand-side solves. One object per thread: it owns its
// cholmod_common.
#include <cholmod.h>

#include <Eigen/Sparse>

#include "sflsh/core/types.hpp"

namespace sflsh::basis::detail {

class CholmodLLT {
 public:
  CholmodLLT();
  ~CholmodLLT();
  CholmodLLT(const CholmodLLT&) = delete;
  CholmodLLT& operator=(const CholmodLLT&) = delete;

  /// Factors the symmetric positive-definite n by n matrix A (only its lower
  /// triangle is read). Fails naming `what` if A is not positive definite.
  void factor(const Eigen::SparseMatrix<double>& A, const char* what);
  /// Solves A X = B for the n by m dense B.
  MatX solve(const MatX& B);
  /// Nonzeros of the Cholesky factor (for reports).
  long factor_nonzeros() const;

 private:
  cholmod_common c_;
  cholmod_factor* L_ = nullptr;
};

}  // namespace sflsh::basis::detail
