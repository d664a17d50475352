#include "sflsh/bench/soft_tissue_modes.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

#include <Eigen/SparseCholesky>
#include <Spectra/SymEigsShiftSolver.h>

#include "sflsh/core/error.hpp"
#include "sflsh/fem/tet_operators.hpp"
#include "sflsh/sim/energies/elastic.hpp"
#include "sflsh/sim/material.hpp"

namespace sflsh {

Eigen::SparseMatrix<double> nodal_stiffness(const TetMesh& mesh, const TetHessian& hessian) {
  const VecX volume = fem::tet_volumes(mesh);
  const std::vector<fem::TetGradient> grads = fem::tet_gradients(mesh);
  std::vector<Eigen::Triplet<double>> entries;
  entries.reserve(size_t(mesh.num_elements()) * 144);
  Eigen::Matrix<double, 9, 9> H;
  Eigen::Matrix<double, 9, 12> G;
  for (int t = 0; t < mesh.num_elements(); ++t) {
    if (!hessian(t, H)) continue;
    require(H.allFinite(), "nodal_stiffness: tet ", t, " has a non-finite Hessian");
    // vec(∇u)_{a+3b} = Σ_n u_{n,a} ∂_b φ_n: column 3n + a, row a + 3b.
    G.setZero();
    for (int n = 0; n < 4; ++n)
      for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b) G(a + 3 * b, 3 * n + a) = grads[size_t(t)](n, b);
    const Eigen::Matrix<double, 12, 12> Kt = std::abs(volume[t]) * G.transpose() * H * G;
    for (int r = 0; r < 12; ++r)
      for (int c = 0; c < 12; ++c)
        entries.emplace_back(3 * mesh.elements(t, r / 3) + r % 3, 3 * mesh.elements(t, c / 3) + c % 3, Kt(r, c));
  }
  Eigen::SparseMatrix<double> K(3 * mesh.num_nodes(), 3 * mesh.num_nodes());
  K.setFromTriplets(entries.begin(), entries.end());
  return K;
}

namespace {

/// y = (A − σ I)⁻¹ x for A = M^{-1/2} K M^{-1/2} on the free DoFs:
/// y = M^{1/2} (K − σ M)⁻¹ M^{1/2} x, one Cholesky factorization per shift.
class ShiftInvertOperator {
 public:
  using Scalar = double;
  ShiftInvertOperator(const Eigen::SparseMatrix<double>& K, const VecX& mass)
      : K_(K), mass_(mass), sqrt_m_(mass.cwiseSqrt()) {}
  Eigen::Index rows() const { return K_.rows(); }
  Eigen::Index cols() const { return K_.cols(); }
  void set_shift(double sigma) {
    Eigen::SparseMatrix<double> S = K_;
    if (sigma != 0.0) S.diagonal() -= sigma * mass_;  // K − σM (K's diagonal is stored: K_ii > 0)
    llt_.compute(S);
    require(llt_.info() == Eigen::Success,
            "vibration modes: the stiffness on the free nodes is not positive definite (a free part of the "
            "mesh is not held by any fixed node?)");
  }
  void perform_op(const double* x_in, double* y_out) const {
    const Eigen::Map<const VecX> x(x_in, rows());
    Eigen::Map<VecX> y(y_out, rows());
    y = sqrt_m_.cwiseProduct(llt_.solve(sqrt_m_.cwiseProduct(x)));
  }

 private:
  const Eigen::SparseMatrix<double>& K_;
  VecX mass_, sqrt_m_;
  Eigen::SimplicialLLT<Eigen::SparseMatrix<double>> llt_;
};

}  // namespace

VibrationModes lowest_vibration_modes(const Eigen::SparseMatrix<double>& K, const VecX& mass, int count) {
  const Eigen::Index N = mass.size();
  const int d = N > 0 && K.rows() % N == 0 ? int(K.rows() / N) : 0;  // DoFs per node
  require((d == 1 || d == 3) && K.cols() == K.rows(), "vibration modes: stiffness is ", K.rows(), " by ", K.cols(),
          ", expected ", N, " or ", 3 * N, " square for ", N, " nodal masses");
  std::vector<int> free;  // DoF indices
  for (Eigen::Index i = 0; i < N; ++i) {
    require(std::isfinite(mass[i]) && mass[i] >= 0, "vibration modes: node ", i, " has mass ", mass[i],
            " (must be finite and >= 0)");
    if (mass[i] > 0)
      for (int c = 0; c < d; ++c) free.push_back(int(d * i + c));
  }
  const int n = int(free.size());
  require(count >= 1 && count < n, "vibration modes: ", count, " modes asked of ", n,
          " free DoFs (must be in [1, free DoFs - 1])");
  // K and M on the free DoFs.
  std::vector<int> index(size_t(d * N), -1);
  for (int f = 0; f < n; ++f) index[size_t(free[size_t(f)])] = f;
  std::vector<Eigen::Triplet<double>> entries;
  for (int c = 0; c < K.outerSize(); ++c)
    for (Eigen::SparseMatrix<double>::InnerIterator it(K, c); it; ++it)
      if (index[size_t(it.row())] >= 0 && index[size_t(it.col())] >= 0)
        entries.emplace_back(index[size_t(it.row())], index[size_t(it.col())], it.value());
  Eigen::SparseMatrix<double> Kf(n, n);
  Kf.setFromTriplets(entries.begin(), entries.end());
  VecX mf(n);
  for (int f = 0; f < n; ++f) mf[f] = mass[free[size_t(f)] / d];

  ShiftInvertOperator op(Kf, mf);
  const int ncv = std::min(n, std::max(2 * count + 1, count + 20));
  Spectra::SymEigsShiftSolver<ShiftInvertOperator> eigs(op, count, ncv, 0.0);
  eigs.init();
  eigs.compute(Spectra::SortRule::LargestMagn, 1000, 1e-10);
  require(eigs.info() == Spectra::CompInfo::Successful, "vibration modes: Lanczos did not converge for ", count,
          " modes of ", n, " free DoFs");
  const VecX lambda = eigs.eigenvalues();  // descending in 1/(λ − σ): ascending λ after sorting
  const MatX psi = eigs.eigenvectors();
  std::vector<int> order(static_cast<size_t>(count));
  for (int k = 0; k < count; ++k) order[size_t(k)] = k;
  std::sort(order.begin(), order.end(), [&](int a, int b) { return lambda[a] < lambda[b]; });
  VibrationModes out;
  out.phi = MatX::Zero(d * N, count);
  out.omega2.resize(count);
  for (int k = 0; k < count; ++k) {
    const int s = order[size_t(k)];
    out.omega2[k] = lambda[s];
    for (int f = 0; f < n; ++f) out.phi(free[size_t(f)], k) = psi(f, s) / std::sqrt(mf[f]);  // φ = M^{-1/2} ψ
  }
  return out;
}

VecX simulated_lumped_mass(const Avatar& a) {
  const VecX volume = fem::tet_volumes(a.tet);
  VecX mass = VecX::Zero(a.tet.num_nodes());
  for (int t = 0; t < a.tet.num_elements(); ++t)
    for (int c = 0; c < 4; ++c) {
      const int i = a.tet.elements(t, c);
      if (a.node_role[i] == int(NodeRole::Simulated)) mass[i] += tet_material(a, t).density * std::abs(volume[t]) / 4;
    }
  return mass;
}

VibrationModes soft_tissue_modes(const Avatar& a, int count) {
  const Eigen::SparseMatrix<double> K = nodal_stiffness(a.tet, [&a](int t, Eigen::Matrix<double, 9, 9>& H) {
    H = linearized_hessian(MaterialPoint(tet_material(a, t), tet_frame(a, t)));
    return true;
  });
  return lowest_vibration_modes(K, simulated_lumped_mass(a), count);
}

VibrationModes skinning_eigenmodes(const Avatar& a, int count) {
  VecX mu(a.tet.num_elements());  // mean of the three Young's moduli, isotropic
  for (int t = 0; t < a.tet.num_elements(); ++t) {
    const RegionMaterial& m = tet_material(a, t);
    mu[t] = (m.young_along + m.young_through + m.young_around) / 3 / (2 * (1 + m.poisson));
  }
  return lowest_vibration_modes(fem::stiffness_laplacian(a.tet, mu), simulated_lumped_mass(a), count);
}

}  // namespace sflsh
