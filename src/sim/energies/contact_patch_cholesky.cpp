#include "sim/energies/contact_patch_cholesky.hpp"

#include <algorithm>
#include <atomic>
#include <vector>

#include <Eigen/OrderingMethods>
#include <Eigen/SparseCholesky>

#include "sflsh/core/error.hpp"

namespace sflsh::contact_patch_detail {

namespace {
using Sparse = Eigen::SparseMatrix<double>;
using Permutation = Eigen::PermutationMatrix<Eigen::Dynamic, Eigen::Dynamic, int>;
std::atomic<long> next_stamp{1};
}  // namespace

struct PatchPattern::Impl {
  long n = 0;
  bool analyzed = false;
  long stamp = 0;  // this pattern's identity and version (unique over all patterns)
  long analyses = 0;
  // The fill-reducing ordering: the factored matrix is M = P A Pᵀ, stored
  // permuted (its upper triangle, which the factorization reads in place, so
  // a factorization does not permute the matrix again).
  Permutation P;
  Sparse upper;  // M's pattern (the values are the factors')
  // The pattern by the dense matrix's lower columns: for column j, the entries
  // first[j] .. first[j + 1] − 1, each the dense row i ≥ j and the position of
  // M's entry (P(i), P(j)) in upper's values.
  std::vector<int> first, row, value;

  // The pattern: the diagonal, the nonzeros of A's and B's lower triangles
  // and, for a matrix of the same size, the last pattern (patterns only widen
  // while the patch keeps its size, so the analysis is redone rarely).
  void analyze(const MatX& A, const MatX* B) {
    const long size = A.rows();
    const bool widen = analyzed && n == size;
    std::vector<Eigen::Triplet<double>> entries;
    for (long j = 0; j < size; ++j) {
      long e = widen ? first[size_t(j)] : 0;
      for (long i = j; i < size; ++i) {
        const bool before = widen && e < first[size_t(j) + 1] && row[size_t(e)] == i;
        if (before) ++e;
        if (i == j || A(i, j) != 0 || (B && (*B)(i, j) != 0) || before) entries.emplace_back(int(i), int(j), 1.0);
      }
    }
    Sparse lower(size, size);
    lower.setFromTriplets(entries.begin(), entries.end());
    // The ordering Eigen's SimplicialLLT would choose (AMD on the full pattern).
    Permutation P_inverse;
    const Sparse full = lower.selfadjointView<Eigen::Lower>();
    Eigen::AMDOrdering<int>()(full, P_inverse);
    P = P_inverse.inverse();
    const auto& to = P.indices();  // dense index i → M's index to[i]
    std::vector<Eigen::Triplet<double>> permuted;
    permuted.reserve(entries.size());
    for (const auto& t : entries) {
      const int a = to[t.row()], b = to[t.col()];
      permuted.emplace_back(std::min(a, b), std::max(a, b), 0.0);
    }
    upper.resize(size, size);
    upper.setFromTriplets(permuted.begin(), permuted.end());
    upper.makeCompressed();
    first.assign(size_t(size) + 1, 0);
    row.resize(entries.size());
    value.resize(entries.size());
    for (size_t k = 0; k < entries.size(); ++k) {  // the triplets are in column order, rows increasing
      const int i = entries[k].row(), j = entries[k].col();
      ++first[size_t(j) + 1];
      row[k] = i;
      value[k] = int(position(to[i], to[j]));
    }
    for (long j = 0; j < size; ++j) first[size_t(j) + 1] += first[size_t(j)];
    analyzed = true;
    n = size;
    stamp = next_stamp++;
    ++analyses;
  }

  // The position of M's entry (a, b) (or (b, a)) in upper's values.
  long position(int a, int b) const {
    if (a > b) std::swap(a, b);
    const int* begin = upper.innerIndexPtr() + upper.outerIndexPtr()[b];
    const int* end = upper.innerIndexPtr() + upper.outerIndexPtr()[b + 1];
    return long(std::lower_bound(begin, end, a) - upper.innerIndexPtr());
  }

  // Writes A + sign B + shift I into M's values; false when a nonzero of A or
  // B lies outside the pattern (counted per column, which vectorizes).
  bool fill(const MatX& A, const MatX* B, double sign, double shift, double* values) const {
    for (long j = 0; j < n; ++j) {
      long inside = 0;  // the pattern's entries of this column where A or B is nonzero
      for (int e = first[size_t(j)]; e < first[size_t(j) + 1]; ++e) {
        const long i = row[size_t(e)];
        const double a = A(i, j), b = B ? (*B)(i, j) : 0.0;
        inside += (a != 0 || b != 0);
        values[value[size_t(e)]] = a + sign * b + (i == j ? shift : 0.0);
      }
      const auto a = A.col(j).tail(n - j).array();
      const long nonzero = B ? ((a != 0) || (B->col(j).tail(n - j).array() != 0)).count() : (a != 0).count();
      if (nonzero != inside) return false;
    }
    return true;
  }
};

PatchPattern::PatchPattern() : impl_(std::make_unique<Impl>()) {}
PatchPattern::~PatchPattern() = default;
PatchPattern::PatchPattern(PatchPattern&&) noexcept = default;
PatchPattern& PatchPattern::operator=(PatchPattern&&) noexcept = default;
PatchPattern::PatchPattern(const PatchPattern& other) : PatchPattern() { *this = other; }
PatchPattern& PatchPattern::operator=(const PatchPattern& other) {
  if (this == &other) return *this;
  impl_ = std::make_unique<Impl>(other.impl_ ? *other.impl_ : Impl());
  impl_->stamp = next_stamp++;
  return *this;
}
long PatchPattern::analyses() const { return impl_ ? impl_->analyses : 0; }

struct PatchCholesky::Impl {
  long n = 0;
  bool ok = false;
  long stamp = -1;  // the pattern's stamp that upper, P and the symbolic analysis are of
  Permutation P;
  Sparse upper;  // M = P A Pᵀ, upper triangle
  Eigen::SimplicialLLT<Sparse, Eigen::Upper, Eigen::NaturalOrdering<int>> llt;
  PatchPattern own;  // for factor(A, ...)

  void sync(const PatchPattern::Impl& p) {
    if (stamp == p.stamp) return;
    n = p.n;
    P = p.P;
    upper = p.upper;
    llt.analyzePattern(upper);
    stamp = p.stamp;
  }
};

PatchCholesky::PatchCholesky() : impl_(std::make_unique<Impl>()) {}
PatchCholesky::~PatchCholesky() = default;
PatchCholesky::PatchCholesky(PatchCholesky&&) noexcept = default;
PatchCholesky& PatchCholesky::operator=(PatchCholesky&&) noexcept = default;
PatchCholesky::PatchCholesky(const PatchCholesky& other) : PatchCholesky() { *this = other; }

PatchCholesky& PatchCholesky::operator=(const PatchCholesky& other) {
  if (this == &other) return *this;
  if (!other.impl_) return *this = PatchCholesky();
  if (!impl_) impl_ = std::make_unique<Impl>();
  Impl& d = *impl_;
  const Impl& s = *other.impl_;
  d.n = s.n;
  d.stamp = s.stamp;
  d.P = s.P;
  d.upper = s.upper;
  d.own = s.own;
  d.ok = false;
  if (d.stamp >= 0) {
    d.llt.analyzePattern(d.upper);
    if (s.ok) d.llt.factorize(d.upper), d.ok = d.llt.info() == Eigen::Success;
  }
  return *this;
}

bool PatchCholesky::factor(PatchPattern& pattern, const MatX& A, const MatX* B, double sign, double shift) {
  if (!impl_) impl_ = std::make_unique<Impl>();
  Impl& m = *impl_;
  PatchPattern::Impl& p = *pattern.impl_;
  if (!p.analyzed || A.rows() != p.n) p.analyzed = false, p.analyze(A, B);
  m.sync(p);
  if (!p.fill(A, B, sign, shift, m.upper.valuePtr())) {  // outside the analysed pattern: widen it
    p.analyze(A, B);
    m.sync(p);
    require(p.fill(A, B, sign, shift, m.upper.valuePtr()),
            "PatchCholesky: the pattern does not hold the matrix after its analysis");
  }
  m.llt.factorize(m.upper);
  m.ok = m.llt.info() == Eigen::Success;
  return m.ok;
}

bool PatchCholesky::factor(const MatX& A, const MatX* B, double sign, double shift) {
  if (!impl_) impl_ = std::make_unique<Impl>();
  return factor(impl_->own, A, B, sign, shift);
}

bool PatchCholesky::ok() const { return impl_ && impl_->ok; }
long PatchCholesky::rows() const { return ok() ? impl_->n : 0; }

VecX PatchCholesky::solve(const VecX& b) const {
  const Impl& m = *impl_;
  return m.P.transpose() * m.llt.solve(m.P * b);  // A⁻¹ = Pᵀ M⁻¹ P
}

void PatchCholesky::half_solve(const MatX& C, MatXr& X) const {
  const Impl& m = *impl_;
  X.resize(C.rows(), C.cols());
  const auto& to = m.P.indices();  // (P C)(to[i], :) = C(i, :)
  for (long i = 0; i < C.rows(); ++i) X.row(to[i]) = C.row(i);
  // L column by column (the diagonal first in each column of a Cholesky factor).
  const Sparse& L = m.llt.matrixL().nestedExpression();
  for (long j = 0; j < L.outerSize(); ++j) {
    Sparse::InnerIterator it(L, j);
    X.row(j) /= it.value();
    for (++it; it; ++it) X.row(it.index()) -= it.value() * X.row(j);
  }
}

}  // namespace sflsh::contact_patch_detail
