#include "sim/energies/contact_patch_cholesky.hpp"

#include <vector>

#include <Eigen/SparseCholesky>

namespace sflsh::contact_patch_detail {

struct PatchCholesky::Impl {
  long n = 0;
  bool ok = false;
  bool analyzed = false;
  std::vector<int> slot;  // dense lower entry (column-major) → index into lower's values, or −1
  Eigen::SparseMatrix<double> lower;
  Eigen::SimplicialLLT<Eigen::SparseMatrix<double>, Eigen::Lower> llt;

  // The pattern: the diagonal, the nonzeros of A's and B's lower triangles
  // and, for a matrix of the same size, the last pattern (patterns only widen
  // while the patch keeps its size, so the analysis is redone rarely).
  void analyze(const MatX& A, const MatX* B) {
    const long size = A.rows();
    const bool widen = analyzed && long(slot.size()) == size * size;
    std::vector<Eigen::Triplet<double>> entries;
    for (long j = 0; j < size; ++j)
      for (long i = j; i < size; ++i)
        if (i == j || A(i, j) != 0 || (B && (*B)(i, j) != 0) || (widen && slot[size_t(j * size + i)] >= 0))
          entries.emplace_back(int(i), int(j), 0.0);
    lower.resize(size, size);
    lower.setFromTriplets(entries.begin(), entries.end());
    lower.makeCompressed();
    slot.assign(size_t(size * size), -1);
    for (long j = 0; j < size; ++j)
      for (Eigen::SparseMatrix<double>::InnerIterator it(lower, j); it; ++it)
        slot[size_t(j * size + it.row())] = int(&it.valueRef() - lower.valuePtr());
    llt.analyzePattern(lower);
    analyzed = true;
    n = size;
  }
};

PatchCholesky::PatchCholesky() : impl_(std::make_unique<Impl>()) {}
PatchCholesky::~PatchCholesky() = default;
PatchCholesky::PatchCholesky(PatchCholesky&&) noexcept = default;
PatchCholesky& PatchCholesky::operator=(PatchCholesky&&) noexcept = default;
PatchCholesky::PatchCholesky(const PatchCholesky& other) : PatchCholesky() { *this = other; }

PatchCholesky& PatchCholesky::operator=(const PatchCholesky& other) {
  if (this == &other) return *this;
  if (!impl_) impl_ = std::make_unique<Impl>();
  Impl& d = *impl_;
  if (!other.impl_) return *this = PatchCholesky();
  const Impl& s = *other.impl_;
  d.n = s.n;
  d.slot = s.slot;
  d.lower = s.lower;
  d.analyzed = s.analyzed;
  d.ok = false;
  if (d.analyzed) {
    d.llt.analyzePattern(d.lower);
    if (s.ok) d.llt.factorize(d.lower), d.ok = d.llt.info() == Eigen::Success;
  }
  return *this;
}

bool PatchCholesky::factor(const MatX& A, const MatX* B, double sign, double shift) {
  if (!impl_) impl_ = std::make_unique<Impl>();
  Impl& m = *impl_;
  const long n = A.rows();
  if (!m.analyzed || n != m.n) m.analyzed = false, m.analyze(A, B);
  double* values = m.lower.valuePtr();
  for (long j = 0; j < n; ++j)
    for (long i = j; i < n; ++i) {
      double v = A(i, j);
      if (B) v += sign * (*B)(i, j);
      if (i == j) v += shift;
      const int s = m.slot[size_t(j * n + i)];
      if (s >= 0) {
        values[s] = v;
      } else if (v != 0) {  // outside the analysed pattern: widen it and start over
        m.analyze(A, B);
        return factor(A, B, sign, shift);
      }
    }
  m.llt.factorize(m.lower);
  m.ok = m.llt.info() == Eigen::Success;
  return m.ok;
}

bool PatchCholesky::ok() const { return impl_ && impl_->ok; }
long PatchCholesky::rows() const { return ok() ? impl_->n : 0; }
VecX PatchCholesky::solve(const VecX& b) const { return impl_->llt.solve(b); }

MatX PatchCholesky::half_solve(const MatX& C) const {
  MatX X = impl_->llt.permutationP() * C;
  impl_->llt.matrixL().solveInPlace(X);
  return X;
}

}  // namespace sflsh::contact_patch_detail
