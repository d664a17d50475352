#include "sflsh/bench/subspace_floor.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include <Eigen/Eigenvalues>

#include "sflsh/core/error.hpp"

namespace sflsh {

SubspaceProjector::SubspaceProjector(const Eigen::SparseMatrix<double, Eigen::RowMajor>& W, const VecX& mass)
    : W_(W), mass_(mass) {
  require(mass.size() == W.rows(), "subspace floor: ", mass.size(), " nodal masses for a basis of ", W.rows(),
          " rows");
  require(mass.allFinite() && (mass.size() == 0 || mass.minCoeff() >= 0.0),
          "subspace floor: nodal masses must be finite and non-negative");
  const Eigen::SparseMatrix<double> MW = mass.asDiagonal() * W;
  const MatX G = MatX(Eigen::SparseMatrix<double>(W.transpose()) * MW);
  for (Eigen::Index k = 0; k < G.rows(); ++k)
    require(G(k, k) > 0.0, "subspace floor: basis column ", k, " has no weight on a node with mass");
  gram_.compute(G);
  require(gram_.info() == Eigen::Success && gram_.isPositive() &&
              gram_.vectorD().minCoeff() > 1e-14 * gram_.vectorD().maxCoeff(),
          "subspace floor: W^T M W is singular (linearly dependent basis columns)");
}

MatX SubspaceProjector::coordinates(const Points& u) const {
  require(u.rows() == W_.rows() && u.cols() == 3, "subspace floor: displacement is ", u.rows(), " by ", u.cols(),
          ", expected ", W_.rows(), " by 3");
  const MatX rhs = W_.transpose() * (mass_.asDiagonal() * MatX(u));
  return gram_.solve(rhs);
}

Points SubspaceProjector::project(const Points& u) const { return W_ * coordinates(u); }

VectorSubspaceProjector::VectorSubspaceProjector(MatX B, const VecX& mass) : B_(std::move(B)) {
  require(B_.rows() == 3 * mass.size(), "subspace floor: vector basis has ", B_.rows(), " rows for ", mass.size(),
          " nodes (expected ", 3 * mass.size(), ")");
  require(mass.allFinite() && (mass.size() == 0 || mass.minCoeff() >= 0.0),
          "subspace floor: nodal masses must be finite and non-negative");
  mass3_.resize(3 * mass.size());
  for (Eigen::Index i = 0; i < mass.size(); ++i) mass3_.segment<3>(3 * i).setConstant(mass[i]);
  const MatX G = B_.transpose() * mass3_.asDiagonal() * B_;
  const Eigen::SelfAdjointEigenSolver<MatX> eig(G);
  const VecX& ev = eig.eigenvalues();
  require(ev.size() > 0 && ev.maxCoeff() > 0.0, "subspace floor: the vector basis has no weight on a node with mass");
  const double floor = 1e-12 * ev.maxCoeff();
  int r = 0;
  for (Eigen::Index k = 0; k < ev.size(); ++k) r += ev[k] > floor;
  kept_.resize(G.rows(), r);
  for (Eigen::Index k = 0, j = 0; k < ev.size(); ++k)
    if (ev[k] > floor) kept_.col(j++) = eig.eigenvectors().col(k) / std::sqrt(ev[k]);
}

Points VectorSubspaceProjector::project(const Points& u) const {
  require(3 * u.rows() == B_.rows() && u.cols() == 3, "subspace floor: displacement is ", u.rows(), " by ", u.cols(),
          ", expected ", B_.rows() / 3, " by 3");
  const Eigen::Map<const VecX> flat(u.data(), u.size());  // Points is row-major: 3i + c
  // c* = Q Qᵀ Bᵀ M u with Q = kept_ (G⁺ restricted to its range).
  const VecX c = kept_ * (kept_.transpose() * (B_.transpose() * mass3_.cwiseProduct(flat)));
  Points out(u.rows(), 3);
  Eigen::Map<VecX>(out.data(), out.size()) = B_ * c;
  return out;
}

MatX vector_basis(const Eigen::SparseMatrix<double, Eigen::RowMajor>& W) {
  MatX B = MatX::Zero(3 * W.rows(), 3 * W.cols());
  for (int i = 0; i < W.outerSize(); ++i)
    for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(W, i); it; ++it)
      for (int c = 0; c < 3; ++c) B(3 * i + c, 3 * it.col() + c) = it.value();
  return B;
}

Eigen::SparseMatrix<double, Eigen::RowMajor> affine_handle_weights(const Eigen::SparseMatrix<double, Eigen::RowMajor>& W,
                                                                   const Points& nodes, const Points& handles) {
  const Eigen::Index N = W.rows(), K = W.cols();
  require(nodes.rows() == N && nodes.cols() == 3, "affine_handle_weights: ", nodes.rows(), " by ", nodes.cols(),
          " node positions for ", N, " rows of W, expected ", N, " by 3");
  require(handles.rows() == K && handles.cols() == 3, "affine_handle_weights: ", handles.rows(), " by ", handles.cols(),
          " handle positions for ", K, " columns of W, expected ", K, " by 3");
  std::vector<Eigen::Triplet<double>> t;
  t.reserve(size_t(4 * W.nonZeros()));
  for (Eigen::Index i = 0; i < N; ++i)
    for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(W, i); it; ++it) {
      const Eigen::Index k = it.col();
      t.emplace_back(int(i), int(k), it.value());
      for (int c = 0; c < 3; ++c)
        t.emplace_back(int(i), int(K + 3 * k + c), it.value() * (nodes(i, c) - handles(k, c)));
    }
  Eigen::SparseMatrix<double, Eigen::RowMajor> out(N, 4 * K);
  out.setFromTriplets(t.begin(), t.end());
  return out;
}

std::vector<double> region_rel_errors(const std::vector<Points>& u, const std::vector<Points>& ref,
                                      const VecXi& region, int num_regions) {
  require(num_regions >= 0, "region errors: negative region count");
  std::vector<double> diff2(size_t(num_regions), 0.0), ref2(size_t(num_regions), 0.0);
  std::vector<long> count(size_t(num_regions), 0);
  const size_t F = std::min(u.size(), ref.size());
  for (size_t f = 0; f < F; ++f) {
    require(u[f].rows() == region.size() && ref[f].rows() == region.size(), "region errors: frame ", f, " has ",
            u[f].rows(), " and ", ref[f].rows(), " points, expected ", region.size(), " (one region label each)");
    for (Eigen::Index v = 0; v < region.size(); ++v) {
      const int r = region[v];
      if (r < 0) continue;
      require(r < num_regions, "region errors: point ", v, " has region ", r, ", expected < ", num_regions);
      diff2[size_t(r)] += (u[f].row(v) - ref[f].row(v)).squaredNorm();
      ref2[size_t(r)] += ref[f].row(v).squaredNorm();
      ++count[size_t(r)];
    }
  }
  std::vector<double> out(size_t(num_regions), std::numeric_limits<double>::quiet_NaN());
  for (int r = 0; r < num_regions; ++r)
    if (count[size_t(r)] > 0 && ref2[size_t(r)] > 0.0) out[size_t(r)] = std::sqrt(diff2[size_t(r)] / ref2[size_t(r)]);
  return out;
}

}  // namespace sflsh
