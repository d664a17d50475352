#include "sflsh/basis/stiffness_fitted_cubature.hpp"

#include <cmath>
#include <utility>
#include <vector>

#include "sflsh/fem/tet_operators.hpp"
#include "sflsh/core/error.hpp"
#include "nonnegative_least_squares.hpp"

namespace sflsh::basis {
namespace {

using Vec9 = Eigen::Matrix<double, 9, 1>;
using HandleGradients = std::vector<std::pair<int, Vec3>>;  // (handle k, d_{t,k}), sorted by k

}  // namespace

Cubature stiffness_fitted_cubature(const TetMesh& mesh, const Eigen::SparseMatrix<double, Eigen::RowMajor>& W,
                                   const VecXi& node_role, const Cubature& candidates, const VecX& tet_modulus,
                                   FittedCubatureReport* report) {
  const int K = int(W.cols()), n = candidates.size();
  require(W.rows() == mesh.num_nodes(), "stiffness_fitted_cubature: W has ", W.rows(), " rows, mesh has ",
          mesh.num_nodes(), " nodes");
  require(tet_modulus.size() == 0 || tet_modulus.size() == mesh.num_elements(), "stiffness_fitted_cubature: ",
          tet_modulus.size(), " tet moduli, expected #T = ", mesh.num_elements());
  require(n > 0 && candidates.weights.size() == n, "stiffness_fitted_cubature: no candidates");
  auto modulus = [&](int t) { return tet_modulus.size() ? tet_modulus[t] : 1.0; };

  // Full tensor T_{kl} (k ≤ l) over all tets.
  const VecX vol = fem::tet_volumes(mesh);
  const std::vector<fem::TetGradient> grads = fem::tet_gradients(mesh);
  std::vector<Mat3> T(size_t(K) * K, Mat3::Zero());
  std::vector<char> used(size_t(K) * K, 0);
  double volume = 0;
  for (int t = 0; t < mesh.num_elements(); ++t) {
    volume += vol[t];
    const HandleGradients d = fem::handle_gradients(mesh, grads[t], W, node_role, t);
    const double s = vol[t] * modulus(t);
    for (size_t i = 0; i < d.size(); ++i)
      for (size_t j = i; j < d.size(); ++j) {
        const size_t p = size_t(d[i].first) * K + d[j].first;
        T[p] += s * d[i].second * d[j].second.transpose();
        used[p] = 1;
      }
  }
  // Equation rows: 9 per used pair, normalized by √(tr T_kk tr T_ll); one volume row.
  std::vector<int> row_of(size_t(K) * K, -1);
  int rows = 0;
  for (size_t p = 0; p < used.size(); ++p)
    if (used[p]) row_of[p] = rows, rows += 9;
  require(rows > 0, "stiffness_fitted_cubature: the basis has no gradient in any tet");
  VecX scale(K);
  for (int k = 0; k < K; ++k) scale[k] = T[size_t(k) * K + k].trace();
  auto pair_scale = [&](int k, int l) {
    const double s = std::sqrt(scale[k] * scale[l]);
    return s > 0 ? 1.0 / s : 0.0;
  };
  constexpr double kVolumeRowWeight = 3.0;
  MatX A = MatX::Zero(rows + 1, n);
  VecX b = VecX::Zero(rows + 1);
  for (size_t p = 0; p < used.size(); ++p) {
    if (!used[p]) continue;
    const int k = int(p / K), l = int(p % K);
    b.segment<9>(row_of[p]) = pair_scale(k, l) * Eigen::Map<const Vec9>(T[p].data());
  }
  b[rows] = kVolumeRowWeight;
  for (int s = 0; s < n; ++s) {
    const int t = candidates.elements[s];
    const HandleGradients d = fem::handle_gradients(mesh, grads[t], W, node_role, t);
    for (size_t i = 0; i < d.size(); ++i)
      for (size_t j = i; j < d.size(); ++j) {
        const size_t p = size_t(d[i].first) * K + d[j].first;
        const Mat3 outer = modulus(t) * d[i].second * d[j].second.transpose();
        A.block<9, 1>(row_of[p], s) = pair_scale(d[i].first, d[j].first) * Eigen::Map<const Vec9>(outer.data());
      }
    A(rows, s) = kVolumeRowWeight / volume;
  }

  // NNLS on the normal equations: min ½ cᵀQc − fᵀc, c ≥ 0.
  const MatX Q = A.transpose() * A;
  const VecX f = A.transpose() * b;
  VecX c = candidates.weights;
  const double initial_error = (A * c - b).head(rows).norm() / b.head(rows).norm();
  const int sweep = nonnegative_least_squares(Q, f, c);

  Cubature out;
  std::vector<int> keep;
  for (int s = 0; s < n; ++s)
    if (c[s] > 1e-9 * c.maxCoeff()) keep.push_back(s);
  out.elements.resize(Eigen::Index(keep.size()));
  out.weights.resize(Eigen::Index(keep.size()));
  out.barycentric.resize(Eigen::Index(keep.size()), 4);
  for (size_t i = 0; i < keep.size(); ++i) {
    out.elements[Eigen::Index(i)] = candidates.elements[keep[i]];
    out.weights[Eigen::Index(i)] = c[keep[i]];
    out.barycentric.row(Eigen::Index(i)) = candidates.barycentric.row(keep[i]);
  }
  if (report) {
    report->candidates = n;
    report->samples = int(keep.size());
    report->sweeps = sweep;
    report->stiffness_error_initial = initial_error;
    report->stiffness_error = (A * c - b).head(rows).norm() / b.head(rows).norm();
    report->volume_error = (c.sum() - volume) / volume;
  }
  return out;
}

}  // namespace sflsh::basis
