#include "basis/cholmod_llt.hpp"

#include "sflsh/core/error.hpp"

namespace sflsh::basis::detail {

CholmodLLT::CholmodLLT() {
  cholmod_start(&c_);
  // AMD only: METIS/NESDIS orderings cost more than they save at our sizes.
  c_.nmethods = 1;
  c_.method[0].ordering = CHOLMOD_AMD;
  c_.postorder = 1;
  c_.print = 0;
  c_.error_handler = nullptr;
}

CholmodLLT::~CholmodLLT() {
  if (L_) cholmod_free_factor(&L_, &c_);
  cholmod_finish(&c_);
}

void CholmodLLT::factor(const Eigen::SparseMatrix<double>& A, const char* what) {
  require(A.rows() == A.cols() && A.isCompressed(), what, ": matrix must be square and compressed");
  cholmod_sparse a{};
  a.nrow = size_t(A.rows());
  a.ncol = size_t(A.cols());
  a.nzmax = size_t(A.nonZeros());
  a.p = const_cast<int*>(A.outerIndexPtr());
  a.i = const_cast<int*>(A.innerIndexPtr());
  a.x = const_cast<double*>(A.valuePtr());
  a.stype = -1;  // symmetric, lower triangle stored/used
  a.itype = CHOLMOD_INT;
  a.xtype = CHOLMOD_REAL;
  a.dtype = CHOLMOD_DOUBLE;
  a.sorted = 1;
  a.packed = 1;
  if (L_) cholmod_free_factor(&L_, &c_);
  L_ = cholmod_analyze(&a, &c_);

  require(L_ != nullptr, what, ": CHOLMOD analysis failed (status ", c_.status, ")");
  cholmod_factorize(&a, L_, &c_);
  require(c_.status == CHOLMOD_OK, what, ": CHOLMOD factorization failed (status ", c_.status,
          c_.status == CHOLMOD_NOT_POSDEF ? ", matrix not positive definite" : "", ")");
}

MatX CholmodLLT::solve(const MatX& B) {
  require(L_ != nullptr, "CholmodLLT::solve called before factor");
  require(size_t(B.rows()) == L_->n, "CholmodLLT::solve: right-hand side has ", B.rows(), " rows, expected ",
          L_->n);
  cholmod_dense b{};
  b.nrow = size_t(B.rows());
  b.ncol = size_t(B.cols());
  b.nzmax = b.nrow * b.ncol;
  b.d = b.nrow;
  b.x = const_cast<double*>(B.data());
  b.xtype = CHOLMOD_REAL;
  b.dtype = CHOLMOD_DOUBLE;
  cholmod_dense* x = cholmod_solve(CHOLMOD_A, L_, &b, &c_);
  require(x != nullptr, "CHOLMOD solve failed (status ", c_.status, ")");
  MatX X = Eigen::Map<const MatX>(static_cast<const double*>(x->x), B.rows(), B.cols());
  cholmod_free_dense(&x, &c_);
  return X;
}

long CholmodLLT::factor_nonzeros() const {
  if (!L_) return 0;
  if (L_->is_super) return long(L_->xsize);
  return L_->nzmax;
}

}  // namespace sflsh::basis::detail
