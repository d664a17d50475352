#pragma once
// The full-FEM reference's sparse Cholesky (CHOLMOD) state, shared by its
// elastic solve (full_fem.cpp) and its contact Hessian blocks (full_fem_contact.cpp).
#include <cholmod.h>

#include <Eigen/Sparse>

#include "sflsh/core/error.hpp"
#include "sflsh/reference/full_fem.hpp"

namespace sflsh {

/// CHOLMOD state: the lower-triangular CSC matrix (Eigen storage, wrapped without
/// copying), the symbolic analysis (once) and the numeric factor (per iteration).
struct FullFem::Cholmod {
  cholmod_common common;
  cholmod_factor* factor = nullptr;
  Eigen::SparseMatrix<double, Eigen::ColMajor, int> H;  // lower triangle only

  Cholmod() {
    cholmod_start(&common);
    common.supernodal = CHOLMOD_SUPERNODAL;
    common.print = 0;
  }
  ~Cholmod() {
    if (factor) cholmod_free_factor(&factor, &common);
    cholmod_finish(&common);
  }
  cholmod_sparse view() {
    cholmod_sparse A{};
    A.nrow = A.ncol = size_t(H.rows());
    A.nzmax = size_t(H.nonZeros());
    A.p = H.outerIndexPtr();
    A.i = H.innerIndexPtr();
    A.x = H.valuePtr();
    A.stype = -1;  // symmetric, lower triangle stored
    A.itype = CHOLMOD_INT;
    A.xtype = CHOLMOD_REAL;
    A.dtype = CHOLMOD_DOUBLE;
    A.sorted = 1;
    A.packed = 1;
    return A;
  }
  /// Drops the factor (and its symbolic analysis) for a new pattern.
  void reset_factor() {
    if (factor) cholmod_free_factor(&factor, &common);
    factor = nullptr;
  }
  /// Factorizes H (analysing on first use); false if not positive definite.
  bool factorize() {
    cholmod_sparse A = view();
    if (!factor) {
      factor = cholmod_analyze(&A, &common);
      require(factor != nullptr, "FullFem: CHOLMOD analyze failed (status ", common.status, ")");
    }
    cholmod_factorize(&A, factor, &common);
    return common.status == CHOLMOD_OK && factor->minor == factor->n;
  }
  VecX solve(const VecX& b) {
    cholmod_dense B{};
    B.nrow = size_t(b.size());
    B.ncol = 1;
    B.nzmax = size_t(b.size());
    B.d = size_t(b.size());
    B.x = const_cast<double*>(b.data());
    B.xtype = CHOLMOD_REAL;
    B.dtype = CHOLMOD_DOUBLE;
    cholmod_dense* X = cholmod_solve(CHOLMOD_A, factor, &B, &common);
    require(X != nullptr, "FullFem: CHOLMOD solve failed (status ", common.status, ")");
    VecX x = Eigen::Map<VecX>(static_cast<double*>(X->x), b.size());
    cholmod_free_dense(&X, &common);
    return x;
  }
};

}  // namespace sflsh
