#include "sim/energies/contact_patch_cholesky.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <vector>

#include <Eigen/OrderingMethods>
#include <Eigen/SparseCore>

#include "sflsh/core/error.hpp"

namespace sflsh::contact_patch_detail {

// The patch block comes in 3x3 node blocks (3 DoFs per node; the nodes
// couple through shared tets, touching faces and their own inertia), so the
// factor is one of node blocks: the ordering is found on the node graph, and
// the left-looking factorization and the solves work on 3x3 blocks.

namespace {
std::atomic<long> next_stamp{1};

// The lower Cholesky factor of a symmetric 3x3 block (its lower triangle is
// read); false when a pivot is not positive.
bool block_cholesky(Mat3& D) {
  const double d0 = D(0, 0);
  if (!(d0 > 0)) return false;
  const double l00 = std::sqrt(d0), l10 = D(1, 0) / l00, l20 = D(2, 0) / l00;
  const double d1 = D(1, 1) - l10 * l10;
  if (!(d1 > 0)) return false;
  const double l11 = std::sqrt(d1), l21 = (D(2, 1) - l20 * l10) / l11;
  const double d2 = D(2, 2) - l20 * l20 - l21 * l21;
  if (!(d2 > 0)) return false;
  D << l00, 0, 0, l10, l11, 0, l20, l21, std::sqrt(d2);
  return true;
}
}  // namespace

struct PatchPattern::Impl {
  long n = 0;       // DoFs (3 per node)
  int nodes = 0;
  bool analyzed = false;
  long stamp = 0;  // this pattern's identity and version (unique over all patterns)
  long analyses = 0;
  // The fill-reducing ordering of the nodes (AMD on the node graph): node i
  // of the dense matrix is node to[i] of the factored M = P A Pᵀ.
  std::vector<int> to;
  // L's block pattern by columns of M: column J holds the rows col_row[p],
  // p = col_first[J] .. col_first[J + 1] − 1, increasing, the diagonal first.
  std::vector<int> col_first, col_row;
  // L's rows: row J's blocks left of the diagonal, (column K, position in column K).
  std::vector<int> row_first;
  std::vector<std::pair<int, int>> row_entry;
  // The dense matrix's pattern by its lower node columns: for node column j,
  // the blocks a_first[j] .. a_first[j + 1] − 1, each its node row i ≥ j, the
  // position of M's block in L's storage and whether it is stored transposed
  // (when the ordering puts node i before node j).
  std::vector<int> a_first, a_row, a_position;
  std::vector<char> a_transposed;

  static bool block_nonzero(const MatX& A, const MatX* B, int i, int j) {
    for (int b = 0; b < 3; ++b)
      for (int a = 0; a < 3; ++a)
        if (A(3 * i + a, 3 * j + b) != 0 || (B && (*B)(3 * i + a, 3 * j + b) != 0)) return true;
    return false;
  }

  // The pattern: the diagonal blocks, the nonzero blocks of A's and B's lower
  // triangles and, for a matrix of the same size, the last pattern (patterns
  // only widen while the patch keeps its size, so the analysis is redone rarely).
  void analyze(const MatX& A, const MatX* B) {
    require(A.rows() % 3 == 0 && A.rows() == A.cols() && (!B || (B->rows() == A.rows() && B->cols() == A.cols())),
            "PatchCholesky: expected square matrices of 3x3 node blocks, got ", A.rows(), " by ", A.cols());
    const long size = A.rows();
    const int N = int(size / 3);
    const bool widen = analyzed && n == size;
    std::vector<std::vector<int>> lower(static_cast<size_t>(N));  // node rows i >= j per node column j
    for (int j = 0; j < N; ++j) {
      int e = widen ? a_first[size_t(j)] : 0;
      for (int i = j; i < N; ++i) {
        const bool before = widen && e < a_first[size_t(j) + 1] && a_row[size_t(e)] == i;
        if (before) ++e;
        if (i == j || before || block_nonzero(A, B, i, j)) lower[size_t(j)].push_back(i);
      }
    }
    // AMD on the node graph (the ordering acts on the full symmetric pattern).
    std::vector<Eigen::Triplet<double>> entries;
    for (int j = 0; j < N; ++j)
      for (int i : lower[size_t(j)]) {
        entries.emplace_back(i, j, 1.0);
        if (i != j) entries.emplace_back(j, i, 1.0);
      }
    Eigen::SparseMatrix<double> graph(N, N);
    graph.setFromTriplets(entries.begin(), entries.end());
    Eigen::PermutationMatrix<Eigen::Dynamic, Eigen::Dynamic, int> P_inverse;
    Eigen::AMDOrdering<int>()(graph, P_inverse);
    to.assign(size_t(N), 0);
    for (int k = 0; k < N; ++k) to[size_t(P_inverse.indices()[k])] = k;
    // M's lower pattern by columns, then L's by the elimination tree: column
    // J holds M's rows and, less J, the rows of each column whose first
    // off-diagonal row is J.
    std::vector<std::vector<int>> column(static_cast<size_t>(N));
    for (int j = 0; j < N; ++j)
      for (int i : lower[size_t(j)]) {
        const int a = to[size_t(i)], b = to[size_t(j)];
        column[size_t(std::min(a, b))].push_back(std::max(a, b));
      }
    std::vector<std::vector<int>> children(static_cast<size_t>(N));
    std::vector<int> mark(size_t(N), -1);
    col_first.assign(size_t(N) + 1, 0);
    col_row.clear();
    for (int J = 0; J < N; ++J) {
      std::vector<int>& rows = column[size_t(J)];
      for (int K : children[size_t(J)])
        for (int p = col_first[size_t(K)] + 1; p < col_first[size_t(K) + 1]; ++p) rows.push_back(col_row[size_t(p)]);
      std::vector<int> unique;
      mark[size_t(J)] = J;
      unique.push_back(J);
      for (int I : rows)
        if (mark[size_t(I)] != J) mark[size_t(I)] = J, unique.push_back(I);
      std::sort(unique.begin() + 1, unique.end());
      col_row.insert(col_row.end(), unique.begin(), unique.end());
      col_first[size_t(J) + 1] = int(col_row.size());
      if (unique.size() > 1) children[size_t(unique[1])].push_back(J);
      std::vector<int>().swap(rows);
    }
    row_first.assign(size_t(N) + 1, 0);
    for (int K = 0; K < N; ++K)
      for (int p = col_first[size_t(K)] + 1; p < col_first[size_t(K) + 1]; ++p) ++row_first[size_t(col_row[size_t(p)]) + 1];
    for (int J = 0; J < N; ++J) row_first[size_t(J) + 1] += row_first[size_t(J)];
    row_entry.assign(size_t(row_first[size_t(N)]), {0, 0});
    std::vector<int> fill = row_first;
    for (int K = 0; K < N; ++K)  // K increasing: each row's entries by increasing column
      for (int p = col_first[size_t(K)] + 1; p < col_first[size_t(K) + 1]; ++p)
        row_entry[size_t(fill[size_t(col_row[size_t(p)])]++)] = {K, p};
    a_first.assign(size_t(N) + 1, 0);
    a_row.clear();
    a_position.clear();
    a_transposed.clear();
    for (int j = 0; j < N; ++j) {
      for (int i : lower[size_t(j)]) {
        const int a = to[size_t(i)], b = to[size_t(j)];
        const int I = std::max(a, b), J = std::min(a, b);
        const auto begin = col_row.begin() + col_first[size_t(J)], end = col_row.begin() + col_first[size_t(J) + 1];
        a_row.push_back(i);
        a_position.push_back(int(std::lower_bound(begin, end, I) - col_row.begin()));
        a_transposed.push_back(a < b);
      }
      a_first[size_t(j) + 1] = int(a_row.size());
    }
    analyzed = true;
    n = size;
    nodes = N;
    stamp = next_stamp++;
    ++analyses;
  }

  // Writes M's blocks of A + sign B + shift I into `L` (zero elsewhere);
  // false when a nonzero of A or B lies outside the pattern (counted per DoF
  // column, which vectorizes).
  bool fill(const MatX& A, const MatX* B, double sign, double shift, std::vector<Mat3>& L) const {
    L.assign(col_row.size(), Mat3::Zero());
    for (int j = 0; j < nodes; ++j) {
      Eigen::Array3i inside = Eigen::Array3i::Zero();  // per DoF column: pattern entries (on or below the diagonal) where A or B is nonzero
      for (int e = a_first[size_t(j)]; e < a_first[size_t(j) + 1]; ++e) {
        const int i = a_row[size_t(e)];
        Mat3 block = A.block<3, 3>(3 * i, 3 * j);
        if (B) block += sign * B->block<3, 3>(3 * i, 3 * j);
        for (int b = 0; b < 3; ++b)
          for (int a = (i == j ? b : 0); a < 3; ++a)
            inside[b] += (A(3 * i + a, 3 * j + b) != 0 || (B && (*B)(3 * i + a, 3 * j + b) != 0));
        if (i == j) {  // the lower triangle is read
          block.diagonal().array() += shift;
          const Mat3 lower_part = block;
          block = lower_part.selfadjointView<Eigen::Lower>();
        }
        L[size_t(a_position[size_t(e)])] = a_transposed[size_t(e)] ? Mat3(block.transpose()) : block;
      }
      for (int b = 0; b < 3; ++b) {
        const long c = 3 * j + b;
        const auto a = A.col(c).tail(n - c).array();
        const long nonzero = B ? ((a != 0) || (B->col(c).tail(n - c).array() != 0)).count() : (a != 0).count();
        if (nonzero != inside[b]) return false;
      }
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
  bool ok = false;
  long stamp = -1;  // the stamp of the pattern this factor's structure is a copy of
  // The structure the factor was made on (a copy: the shared pattern may widen later).
  std::vector<int> to, col_first, col_row, row_first;
  std::vector<std::pair<int, int>> row_entry;
  std::vector<Mat3> L;      // L's blocks (column J's diagonal block lower triangular)
  std::vector<int> scatter;  // per node row: its position in the column being factored
  PatchPattern own;          // for factor(A, ...)

  int nodes() const { return int(to.size()); }

  void sync(const PatchPattern::Impl& p) {
    if (stamp == p.stamp) return;
    to = p.to;
    col_first = p.col_first;
    col_row = p.col_row;
    row_first = p.row_first;
    row_entry = p.row_entry;
    scatter.assign(size_t(p.nodes), -1);
    stamp = p.stamp;
  }

  // Left-looking: column J gathers the updates of the columns its row holds,
  // then is scaled by its diagonal block's factor. False at a pivot ≤ 0.
  bool factorize() {
    const int N = nodes();
    for (int J = 0; J < N; ++J) {
      const int begin = col_first[size_t(J)], end = col_first[size_t(J) + 1];
      for (int p = begin; p < end; ++p) scatter[size_t(col_row[size_t(p)])] = p;
      for (int r = row_first[size_t(J)]; r < row_first[size_t(J) + 1]; ++r) {
        const auto [K, pJK] = row_entry[size_t(r)];
        const Mat3 LJKt = L[size_t(pJK)].transpose();
        for (int p = pJK; p < col_first[size_t(K) + 1]; ++p)  // column K's rows from J down
          L[size_t(scatter[size_t(col_row[size_t(p)])])].noalias() -= L[size_t(p)] * LJKt;
      }
      Mat3& D = L[size_t(begin)];
      if (!block_cholesky(D)) return false;
      const Mat3 D_inverse_t = D.triangularView<Eigen::Lower>().solve(Mat3::Identity()).transpose();
      for (int p = begin + 1; p < end; ++p) L[size_t(p)] = L[size_t(p)] * D_inverse_t;
    }
    return true;
  }

  // y ← L⁻¹ y (rows in M's order, 3 per node, each a row block of Y).
  template <typename Rows>
  void forward(Rows& Y) const {
    for (int J = 0; J < nodes(); ++J) {
      const int begin = col_first[size_t(J)];
      L[size_t(begin)].triangularView<Eigen::Lower>().solveInPlace(Y.template middleRows<3>(3 * J));
      for (int p = begin + 1; p < col_first[size_t(J) + 1]; ++p)
        Y.template middleRows<3>(3 * col_row[size_t(p)]).noalias() -= L[size_t(p)] * Y.template middleRows<3>(3 * J);
    }
  }
};

PatchCholesky::PatchCholesky() : impl_(std::make_unique<Impl>()) {}
PatchCholesky::~PatchCholesky() = default;
PatchCholesky::PatchCholesky(PatchCholesky&&) noexcept = default;
PatchCholesky& PatchCholesky::operator=(PatchCholesky&&) noexcept = default;
PatchCholesky::PatchCholesky(const PatchCholesky& other) : PatchCholesky() { *this = other; }
PatchCholesky& PatchCholesky::operator=(const PatchCholesky& other) {
  if (this == &other) return *this;
  impl_ = std::make_unique<Impl>(other.impl_ ? *other.impl_ : Impl());
  return *this;
}

bool PatchCholesky::factor(PatchPattern& pattern, const MatX& A, const MatX* B, double sign, double shift) {
  if (!impl_) impl_ = std::make_unique<Impl>();
  Impl& m = *impl_;
  PatchPattern::Impl& p = *pattern.impl_;
  if (!p.analyzed || A.rows() != p.n) p.analyze(A, B);  // a new size starts over (analyze widens only at its size)
  m.sync(p);
  if (!p.fill(A, B, sign, shift, m.L)) {  // outside the analysed pattern: widen it
    p.analyze(A, B);
    m.sync(p);
    require(p.fill(A, B, sign, shift, m.L), "PatchCholesky: the pattern does not hold the matrix after its analysis");
  }
  m.ok = m.factorize();
  return m.ok;
}

bool PatchCholesky::factor(const MatX& A, const MatX* B, double sign, double shift) {
  if (!impl_) impl_ = std::make_unique<Impl>();
  return factor(impl_->own, A, B, sign, shift);
}

bool PatchCholesky::ok() const { return impl_ && impl_->ok; }
long PatchCholesky::rows() const { return ok() ? 3 * long(impl_->nodes()) : 0; }

VecX PatchCholesky::solve(const VecX& b) const {  // A⁻¹ = Pᵀ L⁻ᵀ L⁻¹ P
  const Impl& m = *impl_;
  const int N = m.nodes();
  VecX y(b.size());
  for (int i = 0; i < N; ++i) y.segment<3>(3 * m.to[size_t(i)]) = b.segment<3>(3 * i);
  m.forward(y);
  for (int J = N - 1; J >= 0; --J) {
    const int begin = m.col_first[size_t(J)];
    for (int p = begin + 1; p < m.col_first[size_t(J) + 1]; ++p)
      y.segment<3>(3 * J).noalias() -= m.L[size_t(p)].transpose() * y.segment<3>(3 * m.col_row[size_t(p)]);
    m.L[size_t(begin)].transpose().triangularView<Eigen::Upper>().solveInPlace(y.segment<3>(3 * J));
  }
  VecX x(b.size());
  for (int i = 0; i < N; ++i) x.segment<3>(3 * i) = y.segment<3>(3 * m.to[size_t(i)]);
  return x;
}

void PatchCholesky::half_solve(const MatX& C, MatXr& X) const {
  const Impl& m = *impl_;
  X.resize(C.rows(), C.cols());
  for (int i = 0; i < m.nodes(); ++i) X.middleRows<3>(3 * m.to[size_t(i)]) = C.middleRows<3>(3 * i);
  m.forward(X);
}

}  // namespace sflsh::contact_patch_detail
