// Vibration modes (a candidate basis) and the vector-basis projector
// that measures their floor: against a closed-form spring chain, a dense
// generalized eigensolver, the linear-elastic energy of a uniform strain, and a
// dense weighted least-squares solve.
#include "sflsh/bench/soft_tissue_modes.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include <Eigen/Eigenvalues>
#include <Eigen/QR>

#include "../basis/box_mesh.hpp"
#include "sflsh/bench/subspace_floor.hpp"
#include "sflsh/core/error.hpp"

namespace sflsh {
namespace {

using Sp = Eigen::SparseMatrix<double>;

/// A chain of n + 1 nodes, springs of stiffness k between neighbours along each
/// axis independently (K = L ⊗ I₃), node 0 held (mass 0), the others mass m.
void spring_chain(int n, double k, double m, Sp* K, VecX* mass) {
  std::vector<Eigen::Triplet<double>> e;
  for (int i = 0; i < n; ++i)
    for (int c = 0; c < 3; ++c) {
      const int a = 3 * i + c, b = 3 * (i + 1) + c;
      e.emplace_back(a, a, k), e.emplace_back(b, b, k), e.emplace_back(a, b, -k), e.emplace_back(b, a, -k);
    }
  K->resize(3 * (n + 1), 3 * (n + 1));
  K->setFromTriplets(e.begin(), e.end());
  *mass = VecX::Constant(n + 1, m);
  (*mass)[0] = 0.0;
}

TEST(VibrationModes, FixedFreeSpringChainMatchesTheClosedForm) {
  // ω_j² = (4k/m) sin²((2j − 1)π / (2(2n + 1))), j = 1..n, each three times (x, y, z).
  const int n = 12;
  const double k = 250.0, m = 0.4;
  Sp K;
  VecX mass;
  spring_chain(n, k, m, &K, &mass);
  const VibrationModes modes = lowest_vibration_modes(K, mass, 9);
  for (int j = 1; j <= 3; ++j) {
    const double s = std::sin((2 * j - 1) * M_PI / (2.0 * (2 * n + 1)));
    const double expected = 4 * k / m * s * s;
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(modes.omega2[3 * (j - 1) + c], expected, 1e-9 * expected) << j;
  }
  // The held node does not move; Φᵀ M Φ = I.
  EXPECT_EQ(modes.phi.topRows(3).norm(), 0.0);
  VecX m3(3 * (n + 1));
  for (int i = 0; i <= n; ++i) m3.segment<3>(3 * i).setConstant(mass[i]);
  const MatX gram = modes.phi.transpose() * m3.asDiagonal() * modes.phi;
  EXPECT_LT((gram - MatX::Identity(9, 9)).lpNorm<Eigen::Infinity>(), 1e-9);
}

TEST(VibrationModes, ScalarFieldsOneDofPerNode) {
  // The same chain as a scalar problem (K N by N): each ω² once, in order.
  const int n = 12;
  const double k = 250.0, m = 0.4;
  std::vector<Eigen::Triplet<double>> e;
  for (int i = 0; i < n; ++i)
    e.emplace_back(i, i, k), e.emplace_back(i + 1, i + 1, k), e.emplace_back(i, i + 1, -k), e.emplace_back(i + 1, i, -k);
  Sp K(n + 1, n + 1);
  K.setFromTriplets(e.begin(), e.end());
  VecX mass = VecX::Constant(n + 1, m);
  mass[0] = 0.0;
  const VibrationModes modes = lowest_vibration_modes(K, mass, 4);
  ASSERT_EQ(modes.phi.rows(), n + 1);
  for (int j = 1; j <= 4; ++j) {
    const double s = std::sin((2 * j - 1) * M_PI / (2.0 * (2 * n + 1)));
    EXPECT_NEAR(modes.omega2[j - 1], 4 * k / m * s * s, 1e-9 * 4 * k / m * s * s) << j;
  }
  EXPECT_EQ(modes.phi(0, 0), 0.0);
  // A stiffness of neither N nor 3N rows is refused.
  EXPECT_THROW(lowest_vibration_modes(Sp(2 * (n + 1), 2 * (n + 1)), mass, 2), Error);
}

TEST(VibrationModes, AgreeWithADenseGeneralizedEigensolver) {
  // A random sparse SPD stiffness with unequal masses and two held nodes.
  const int N = 30;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> U(0.0, 1.0);
  MatX A = MatX::Zero(3 * N, 3 * N);
  for (int i = 0; i < 3 * N; ++i)
    for (int j = 0; j < 3 * N; ++j)
      if (U(rng) < 0.08) A(i, j) = U(rng) - 0.5;
  const MatX Kd = A * A.transpose() + MatX::Identity(3 * N, 3 * N);
  VecX mass = VecX::LinSpaced(N, 0.2, 3.0);
  mass[4] = mass[17] = 0.0;
  const VibrationModes modes = lowest_vibration_modes(Kd.sparseView(), mass, 8);
  // Dense reference on the free DoFs.
  std::vector<int> free;
  for (int i = 0; i < N; ++i)
    if (mass[i] > 0)
      for (int c = 0; c < 3; ++c) free.push_back(3 * i + c);
  const int n = int(free.size());
  MatX Kf(n, n), Mf = MatX::Zero(n, n);
  for (int a = 0; a < n; ++a) {
    Mf(a, a) = mass[free[size_t(a)] / 3];
    for (int b = 0; b < n; ++b) Kf(a, b) = Kd(free[size_t(a)], free[size_t(b)]);
  }
  const Eigen::GeneralizedSelfAdjointEigenSolver<MatX> dense(Kf, Mf);
  for (int k = 0; k < 8; ++k) EXPECT_NEAR(modes.omega2[k], dense.eigenvalues()[k], 1e-9 * dense.eigenvalues()[k]);
  // Each mode satisfies K φ = ω² M φ and is zero on the held nodes.
  VecX m3(3 * N);
  for (int i = 0; i < N; ++i) m3.segment<3>(3 * i).setConstant(mass[i]);
  for (int k = 0; k < 8; ++k) {
    const VecX r = Kd * modes.phi.col(k) - modes.omega2[k] * m3.cwiseProduct(modes.phi.col(k));
    double rf = 0;
    for (int a : free) rf = std::max(rf, std::abs(r[a]));
    EXPECT_LT(rf, 1e-8 * modes.omega2[k]);
    EXPECT_EQ(modes.phi.block(12, k, 3, 1).norm(), 0.0);
  }
}

TEST(VibrationModes, BadInputIsRefusedWithAReason) {
  Sp K;
  VecX mass;
  spring_chain(3, 1.0, 1.0, &K, &mass);
  EXPECT_THROW(lowest_vibration_modes(K, mass, 0), Error);
  EXPECT_THROW(lowest_vibration_modes(K, mass, 9), Error);  // 9 free DoFs
  VecX bad = mass;
  bad[2] = std::nan("");
  EXPECT_THROW(lowest_vibration_modes(K, bad, 2), Error);
  EXPECT_THROW(lowest_vibration_modes(K, mass.head(3), 2), Error);
  // A stiffness that is not positive definite on the free DoFs.
  EXPECT_THROW(lowest_vibration_modes(Sp(-K), mass, 2), Error);
}

/// One tet with the given 4 by 3 nodes.
TetMesh one_tet(const Points& nodes) {
  TetMesh mesh;
  mesh.nodes = nodes;
  mesh.elements.resize(1, 4);
  mesh.elements << 0, 1, 2, 3;
  return mesh;
}

TEST(NodalStiffness, UniformStrainHasTheLinearElasticEnergy) {
  // One tet; H of Ψ = μ ε:ε + (λ/2) tr²ε over vec(∇u) column-major:
  // H = μ (I + T) + λ v vᵀ (T transposes, v = vec I). For u = A x,
  // ½ uᵀ K u = V (μ ε:ε + λ/2 tr²ε) with ε = (A + Aᵀ)/2; a rotation rate has none.
  const TetMesh mesh =
      one_tet((Points(4, 3) << 0.1, 0.0, 0.0, 0.4, 0.05, 0.0, 0.05, 0.3, 0.02, 0.08, 0.1, 0.5).finished());
  const double mu = 3000, lambda = 27000;
  Eigen::Matrix<double, 9, 9> H = mu * Eigen::Matrix<double, 9, 9>::Identity();
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b) {
      H(a + 3 * b, b + 3 * a) += mu;
      H(a + 3 * a, b + 3 * b) += lambda;
    }
  const Sp K = nodal_stiffness(mesh, [&](int, Eigen::Matrix<double, 9, 9>& out) {
    out = H;
    return true;
  });
  const Mat3 A = (Mat3() << 0.01, 0.02, -0.005, 0.0, -0.03, 0.01, 0.004, 0.0, 0.02).finished();
  VecX u(12), w(12), t(12);
  const Mat3 W = (Mat3() << 0, -0.02, 0.01, 0.02, 0, -0.03, -0.01, 0.03, 0).finished();  // skew
  for (int n = 0; n < 4; ++n) {
    const Vec3 x = mesh.nodes.row(n).transpose();
    u.segment<3>(3 * n) = A * x;
    w.segment<3>(3 * n) = W * x;
    t.segment<3>(3 * n) = Vec3(0.3, -0.2, 0.1);
  }
  const Vec3 e1 = mesh.nodes.row(1) - mesh.nodes.row(0), e2 = mesh.nodes.row(2) - mesh.nodes.row(0),
             e3 = mesh.nodes.row(3) - mesh.nodes.row(0);
  const double V = std::abs(e1.dot(e2.cross(e3))) / 6;
  const Mat3 eps = (A + A.transpose()) / 2;
  const double expected = V * (mu * eps.squaredNorm() + lambda / 2 * eps.trace() * eps.trace());
  EXPECT_NEAR(0.5 * u.dot(K * u), expected, 1e-12 * expected);
  EXPECT_LT((K * w).norm(), 1e-9 * (K * u).norm());  // infinitesimal rotation
  EXPECT_LT((K * t).norm(), 1e-9 * (K * u).norm());  // translation
}

TEST(NodalStiffness, GradientEntriesFollowTheColumnMajorLayout) {
  // H = e_k e_kᵀ with k = a + 3b (a = 0, b = 1): energy ½ V (∂u_x/∂y)², not (∂u_y/∂x)².
  const TetMesh mesh = one_tet((Points(4, 3) << 0, 0, 0, 0.2, 0, 0, 0, 0.3, 0, 0, 0, 0.1).finished());
  const Sp K = nodal_stiffness(mesh, [](int, Eigen::Matrix<double, 9, 9>& H) {
    H.setZero();
    H(0 + 3 * 1, 0 + 3 * 1) = 1.0;
    return true;
  });
  const double V = 0.2 * 0.3 * 0.1 / 6;
  VecX u(12), v(12);
  for (int n = 0; n < 4; ++n) {
    const Vec3 x = mesh.nodes.row(n).transpose();
    u.segment<3>(3 * n) = Vec3(0.05 * x.y(), 0, 0);  // ∂u_x/∂y = 0.05
    v.segment<3>(3 * n) = Vec3(0, 0.05 * x.x(), 0);  // ∂u_y/∂x = 0.05
  }
  EXPECT_NEAR(0.5 * u.dot(K * u), 0.5 * V * 0.05 * 0.05, 1e-15);
  EXPECT_NEAR(0.5 * v.dot(K * v), 0.0, 1e-15);
}

TEST(SkinningEigenmodes, BarHeldAtOneEndMatchesTheWaveEquation) {
  // A 1 m bar held at x = 0, free elsewhere: the lowest eigenvalues of
  // μ Δw = −λ ρ w are λ_j = (μ/ρ) ((2j − 1)π / (2L))², with μ = Ē / (2(1 + ν)) from
  // the mean Ē of the three Young's moduli: (3 + 1 + 2)·10⁴ / 3 / 2.9 Pa, ρ = 1000.
  Avatar a;
  a.tet = test::box_tet_mesh(40, 1, 1, 1.0, 0.05, 0.05);
  a.tet_region = VecXi::Zero(a.tet.num_elements());
  RegionMaterial m;
  m.young_along = 3e4, m.young_through = 1e4, m.young_around = 2e4, m.poisson = 0.45, m.density = 1000;
  a.materials = {m};
  a.node_role = VecXi::Constant(a.tet.num_nodes(), int(NodeRole::Simulated));
  for (int i = 0; i < a.tet.num_nodes(); ++i)
    if (a.tet.nodes(i, 0) < 1e-9) a.node_role[i] = int(NodeRole::Bone);
  const VibrationModes modes = skinning_eigenmodes(a, 2);
  const double c2 = 2e4 / 2.9 / 1000.0;
  for (int j = 1; j <= 2; ++j) {
    const double k = (2 * j - 1) * M_PI / 2.0;
    EXPECT_NEAR(modes.omega2[j - 1], c2 * k * k, 0.01 * c2 * k * k) << j;  // P1 + lumped mass: O(h²)
  }
  EXPECT_EQ(modes.phi.rows(), a.tet.num_nodes());
}

TEST(VectorSubspaceProjector, MatchesADenseWeightedLeastSquaresSolve) {
  // A dependent column (the sum of two others) must not change the projection.
  const int N = 25, D = 7;
  std::mt19937 rng(3);
  std::normal_distribution<double> G(0.0, 1.0);
  MatX B(3 * N, D + 1);
  for (int i = 0; i < 3 * N; ++i)
    for (int j = 0; j < D; ++j) B(i, j) = G(rng);
  B.col(D) = B.col(1) + B.col(4);
  VecX mass = VecX::LinSpaced(N, 0.1, 2.5);
  mass[3] = 0.0;  // a held node: its error does not count
  Points u(N, 3);
  for (int i = 0; i < N; ++i)
    for (int c = 0; c < 3; ++c) u(i, c) = G(rng);
  const VectorSubspaceProjector P(B, mass);
  EXPECT_EQ(P.rank(), D);
  const Points p = P.project(u);
  // Reference: min ‖√M (B c − u)‖ by column-pivoted QR on the independent columns.
  VecX s(3 * N), flat(3 * N);
  for (int i = 0; i < N; ++i)
    for (int c = 0; c < 3; ++c) s[3 * i + c] = std::sqrt(mass[i]), flat[3 * i + c] = u(i, c);
  const MatX Bi = B.leftCols(D);
  const VecX c = (s.asDiagonal() * Bi).colPivHouseholderQr().solve(s.cwiseProduct(flat));
  const VecX ref = Bi * c;
  for (int i = 0; i < N; ++i)
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(p(i, k), ref[3 * i + k], 1e-10) << i;
}

TEST(VectorSubspaceProjector, HandlesAsAVectorBasisGiveTheScalarProjection) {
  // vector_basis(W) spans W ⊗ I₃: column 3k + c is W_·k along axis c.
  Eigen::SparseMatrix<double, Eigen::RowMajor> W(4, 2);
  W.insert(0, 0) = 1.0, W.insert(1, 0) = 0.5, W.insert(1, 1) = 0.5, W.insert(2, 1) = 1.0, W.insert(3, 1) = 0.25;
  const MatX B = vector_basis(W);
  ASSERT_EQ(B.rows(), 12);
  ASSERT_EQ(B.cols(), 6);
  EXPECT_EQ(B(3 * 1 + 2, 3 * 0 + 2), 0.5);  // node 1, z, handle 0
  EXPECT_EQ(B(3 * 3 + 0, 3 * 1 + 0), 0.25);
  EXPECT_EQ(B(3 * 3 + 1, 3 * 1 + 0), 0.0);
  const VecX mass = (VecX(4) << 1.0, 2.0, 0.5, 3.0).finished();
  Points u(4, 3);
  u << 1, 2, 3, -1, 0, 2, 0.5, 0.5, -2, 4, 1, 0;
  const Points a = VectorSubspaceProjector(B, mass).project(u);
  const Points b = SubspaceProjector(W, mass).project(u);
  EXPECT_LT((a - b).lpNorm<Eigen::Infinity>(), 1e-12);
}

}  // namespace
}  // namespace sflsh
