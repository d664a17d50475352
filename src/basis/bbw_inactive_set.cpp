// The inactive-set systems of one column of the bounded biharmonic weights:
// one CHOLMOD factor over a base set, updated by bordering (see InactiveSetSolver).
#include <algorithm>

#include "basis/bbw_internal.hpp"

namespace sflsh::basis::bbw_internal {

namespace {

/// Rows/cols `keep` (ascending) of the symmetric column-major A; `map[i]` is
/// the new index of old index i or −1.
SpMat principal_submatrix(const SpMat& A, const std::vector<int>& keep, const std::vector<int>& map) {
  std::vector<Eigen::Triplet<double>> trip;
  for (size_t c = 0; c < keep.size(); ++c)
    for (SpMat::InnerIterator it(A, keep[c]); it; ++it) {
      const int r = map[it.row()];
      if (r >= int(c)) trip.emplace_back(r, int(c), it.value());  // lower triangle is all CHOLMOD reads
    }
  SpMat S(int(keep.size()), int(keep.size()));
  S.setFromTriplets(trip.begin(), trip.end());
  S.makeCompressed();
  return S;
}

}  // namespace

void InactiveSetSolver::solve(const std::vector<char>& state, const VecX& q, VecX& x) {
  const int n = int(A_.rows());
  std::vector<int> added, held;  // I \ I0, I0 \ I
  int num_free = 0;
  for (int i = 0; i < n; ++i) {
    const bool is_free = state[i] == kFree;
    num_free += is_free;
    if (is_free && base_index_[i] < 0) added.push_back(i);
    if (!is_free && base_index_[i] >= 0) held.push_back(i);
  }
  int uncached = 0;
  for (int j : added) uncached += cache_col_[j] < 0;
  for (int j : held) uncached += cache_col_[j] < 0;
  if (!factored_ || cache_cols_ + uncached > max_border_) {
    refactor(state, num_free);
    added.clear(), held.clear();
  }
  const bool bordered = !added.empty() || !held.empty();
  // Right-hand side with every node of I0 ∪ added unknown: r = −q − Q x_out.
  VecX xo = x;
  for (int i : base_) xo(i) = 0.0;
  for (int i : added) xo(i) = 0.0;
  const VecX r = -(q + A_ * xo);
  MatX r0(base_.size(), 1);
  for (size_t c = 0; c < base_.size(); ++c) r0(Eigen::Index(c), 0) = r(base_[c]);
  const MatX y0 = llt_.solve(r0);
  if (!bordered) {
    for (size_t c = 0; c < base_.size(); ++c) x(base_[c]) = y0(Eigen::Index(c), 0);
    return;
  }
  // Cache F⁻¹B for new border nodes: B e_j = Q(I0, j) for an added node,
  // the unit vector of j for a held node.
  std::vector<int> fresh;
  for (int j : added)
    if (cache_col_[j] < 0) fresh.push_back(j);
  for (int j : held)
    if (cache_col_[j] < 0) fresh.push_back(j);
  if (!fresh.empty()) {
    MatX B = MatX::Zero(Eigen::Index(base_.size()), Eigen::Index(fresh.size()));
    for (size_t k = 0; k < fresh.size(); ++k) {
      const int j = fresh[k];
      if (base_index_[j] >= 0) {
        B(base_index_[j], Eigen::Index(k)) = 1.0;
      } else {
        for (SpMat::InnerIterator it(A_, j); it; ++it)
          if (base_index_[it.row()] >= 0) B(base_index_[it.row()], Eigen::Index(k)) = it.value();
      }
    }
    const MatX Zn = llt_.solve(B);
    if (Z_.cols() < cache_cols_ + Zn.cols())
      Z_.conservativeResize(Z_.rows(), std::max<Eigen::Index>(cache_cols_ + Zn.cols(), 2 * Z_.cols()));
    Z_.middleCols(cache_cols_, Zn.cols()) = Zn;
    for (size_t k = 0; k < fresh.size(); ++k) cache_col_[fresh[k]] = cache_cols_ + int(k);
    cache_cols_ += int(Zn.cols());
  }
  // Border order: added nodes, then held nodes. S = C − Bᵀ F⁻¹ B.
  std::vector<int> border = added;
  border.insert(border.end(), held.begin(), held.end());
  const int m = int(border.size());
  const int na = int(added.size());
  std::vector<int> zc(m);
  for (int k = 0; k < m; ++k) zc[k] = cache_col_[border[k]];
  MatX S(m, m);
  VecX rhs(m);
  for (int a = 0; a < m; ++a) {
    const int j = border[a];
    // Row a of Bᵀ applied to [F⁻¹B | y0].
    if (a >= na) {
      const int bi = base_index_[j];
      for (int b = 0; b < m; ++b) S(a, b) = -Z_(bi, zc[b]);
      rhs(a) = (state[j] == kUpper ? 1.0 : 0.0) - y0(bi, 0);
    } else {
      S.row(a).setZero();
      rhs(a) = r(j);
      for (SpMat::InnerIterator it(A_, j); it; ++it) {
        const int bi = base_index_[it.row()];
        if (bi < 0) continue;
        for (int b = 0; b < m; ++b) S(a, b) -= it.value() * Z_(bi, zc[b]);
        rhs(a) -= it.value() * y0(bi, 0);
      }
    }
  }
  for (int a = 0; a < na; ++a)  // C: Q between added nodes
    for (int b = 0; b < na; ++b) S(a, b) += A_.coeff(added[a], added[b]);
  const VecX s = S.partialPivLu().solve(rhs);
  VecX y = y0.col(0);
  for (int b = 0; b < m; ++b) y -= s(b) * Z_.col(zc[b]);
  for (size_t c = 0; c < base_.size(); ++c) x(base_[c]) = y(Eigen::Index(c));
  for (int a = 0; a < na; ++a) x(added[a]) = s(a);
  for (int j : held) x(j) = state[j] == kUpper ? 1.0 : 0.0;
}

void InactiveSetSolver::refactor(const std::vector<char>& state, int num_free) {
  for (int i : base_) base_index_[i] = -1;
  base_.clear();
  base_.reserve(size_t(num_free));
  for (int i = 0; i < int(A_.rows()); ++i)
    if (state[i] == kFree) base_index_[i] = int(base_.size()), base_.push_back(i);
  std::fill(cache_col_.begin(), cache_col_.end(), -1);
  cache_cols_ = 0;
  Z_.resize(Eigen::Index(base_.size()), std::min(max_border_, 64));
  llt_.factor(principal_submatrix(A_, base_, base_index_), "bounded biharmonic weights: inactive-set system");
  factored_ = true;
  ++factorizations_;
}

}  // namespace sflsh::basis::bbw_internal
