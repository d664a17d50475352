// The reduced small-strain stiffness with and without mean dilatation
// (sim/linearized_stiffness.hpp), against dense sums written out here from the
// definitions, homogeneous strain, and Jensen's inequality for an isotropic
// material.
#include <random>

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <gtest/gtest.h>

#include "sflsh/core/error.hpp"
#include "sflsh/sim/energies/elastic.hpp"
#include "sflsh/sim/linearized_stiffness.hpp"
#include "synthetic_avatar.hpp"

namespace sflsh {
namespace {

/// vec(∇u_t) = B_t z (9 by 3K), from the tet's own shape-function gradients
/// (rows of the inverse edge matrix) and W on Simulated nodes.
Eigen::Matrix<double, 9, Eigen::Dynamic> dense_B(const Avatar& a, int t) {
  Mat3 D;
  const Vec3 x0 = a.tet.nodes.row(a.tet.elements(t, 0)).transpose();
  for (int c = 1; c < 4; ++c) D.col(c - 1) = a.tet.nodes.row(a.tet.elements(t, c)).transpose() - x0;
  const Mat3 Dinv = D.inverse();
  Eigen::Matrix<double, 4, 3> gradN;
  gradN.bottomRows<3>() = Dinv;
  gradN.row(0) = -Dinv.colwise().sum();
  Eigen::Matrix<double, 9, Eigen::Dynamic> B = Eigen::Matrix<double, 9, Eigen::Dynamic>::Zero(9, a.num_reduced());
  for (int c = 0; c < 4; ++c) {
    const int n = a.tet.elements(t, c);
    if (a.node_role[n] != int(NodeRole::Simulated)) continue;
    for (int h = 0; h < a.num_handles(); ++h) {
      const double w = a.W.coeff(n, h);
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) B(i + 3 * j, 3 * h + i) += w * gradN(c, j);  // ∂(∇u)_ij/∂z_hi
    }
  }
  return B;
}

double tet_volume(const Avatar& a, int t) {
  Mat3 D;
  const Vec3 x0 = a.tet.nodes.row(a.tet.elements(t, 0)).transpose();
  for (int c = 1; c < 4; ++c) D.col(c - 1) = a.tet.nodes.row(a.tet.elements(t, c)).transpose() - x0;
  return std::abs(D.determinant()) / 6.0;
}

Mat9 material_H(const Avatar& a, int t) {
  return linearized_hessian(MaterialPoint(tet_material(a, t), tet_frame(a, t)));
}

test::SyntheticAvatarOptions hat_handles() {
  test::SyntheticAvatarOptions o;
  o.nx = 3, o.ny = 3, o.nz = 2;
  o.handles = 6;
  o.handle_radius = 0.07;
  return o;
}

TEST(LinearizedStiffness, PlainAssemblyEqualsTheDenseSumOverTets) {
  const Avatar a = test::make_synthetic_avatar(hat_handles());
  const MatX K = linearized_stiffness(a, material_tet_stiffness(a), false);
  MatX expected = MatX::Zero(a.num_reduced(), a.num_reduced());
  for (int t = 0; t < a.tet.num_elements(); ++t) {
    const auto B = dense_B(a, t);
    expected += tet_volume(a, t) * B.transpose() * material_H(a, t) * B;
  }
  EXPECT_LE((K - expected).norm(), 1e-10 * expected.norm());
}

TEST(LinearizedStiffness, CellsAreTheLargestSummedHandleWeight) {
  const Avatar a = test::make_synthetic_avatar(hat_handles());
  const VecXi cell = dilatation_cells(a);
  int moving = 0;
  for (int t = 0; t < a.tet.num_elements(); ++t) {
    VecX sum = VecX::Zero(a.num_handles());
    for (int c = 0; c < 4; ++c) {
      const int n = a.tet.elements(t, c);
      if (a.node_role[n] == int(NodeRole::Simulated)) sum += a.W.row(n).transpose();
    }
    if (sum.maxCoeff() <= 0) {
      EXPECT_EQ(cell[t], -1) << "tet " << t;
      continue;
    }
    ++moving;
    ASSERT_GE(cell[t], 0);
    EXPECT_EQ(sum[cell[t]], sum.maxCoeff()) << "tet " << t;
  }
  EXPECT_GT(moving, a.tet.num_elements() / 2);
}

TEST(LinearizedStiffness, MeanDilatationEqualsTheDenseBBarSum) {
  const Avatar a = test::make_synthetic_avatar(hat_handles());
  const VecXi cell = dilatation_cells(a);
  const int n = a.num_reduced();
  // θ_c = g_cᵀ z: the volume-weighted mean of tr ∇u over the cell.
  std::vector<VecX> g(size_t(a.num_handles()), VecX::Zero(n));
  VecX Vc = VecX::Zero(a.num_handles());
  Vec9 v = Vec9::Zero();
  v[0] = v[4] = v[8] = 1;
  for (int t = 0; t < a.tet.num_elements(); ++t) {
    if (cell[t] < 0) continue;
    g[size_t(cell[t])] += tet_volume(a, t) * (v.transpose() * dense_B(a, t)).transpose();
    Vc[cell[t]] += tet_volume(a, t);
  }
  MatX expected = MatX::Zero(n, n);
  for (int t = 0; t < a.tet.num_elements(); ++t) {
    auto B = dense_B(a, t);
    if (cell[t] >= 0) {
      // ∇ū = ∇u − tr(∇u)/3 I + θ_c/3 I
      const Eigen::RowVectorXd tr = v.transpose() * B;
      B -= v * tr / 3.0;
      B += v * (g[size_t(cell[t])] / Vc[cell[t]]).transpose() / 3.0;
    }
    expected += tet_volume(a, t) * B.transpose() * material_H(a, t) * B;
  }
  const MatX K = linearized_stiffness(a, material_tet_stiffness(a), true, 0.0);
  EXPECT_LE((K - expected).norm(), 1e-10 * expected.norm());
  // And it differs from the plain assembly (the test would not see a no-op).
  const MatX K_plain = linearized_stiffness(a, material_tet_stiffness(a), false);
  EXPECT_GT((K - K_plain).norm(), 1e-3 * K_plain.norm());
  // The partial average, written per tet from its definition: the averaged
  // operator B̄ (∇ū) weighted 1 − α and the tet's own B weighted α.
  for (double alpha : {0.2, 0.65}) {
    MatX partial = MatX::Zero(n, n);
    for (int t = 0; t < a.tet.num_elements(); ++t) {
      const auto B = dense_B(a, t);
      if (cell[t] < 0) {
        partial += tet_volume(a, t) * B.transpose() * material_H(a, t) * B;
        continue;
      }
      const Eigen::RowVectorXd tr = v.transpose() * B;
      const MatX dev = B - v * tr / 3.0;
      const MatX bar = dev + v * (g[size_t(cell[t])] / Vc[cell[t]]).transpose() / 3.0;
      const Mat9 H = material_H(a, t);
      partial += tet_volume(a, t) * ((1 - alpha) * bar.transpose() * H * bar + alpha * B.transpose() * H * B);
    }
    const MatX K_alpha = linearized_stiffness(a, material_tet_stiffness(a), true, alpha);
    EXPECT_LE((K_alpha - partial).norm(), 1e-10 * partial.norm()) << "alpha " << alpha;
    EXPECT_LE((K_alpha - ((1 - alpha) * K + alpha * K_plain)).norm(), 1e-10 * K_plain.norm()) << "alpha " << alpha;
  }
  EXPECT_THROW(linearized_stiffness(a, material_tet_stiffness(a), true, 1.5), Error);
}

TEST(LinearizedStiffness, HomogeneousStrainKeepsItsEnergy) {
  // W = identity: z_n = a·y_n makes ∇u = a e_yᵀ in every tet (u = 0 on the
  // bottom layer y = 0, Bone), so every cell's mean dilatation is its tets'
  // own and the energy is Σ_t V_t ½ vec(A)ᵀ H_t vec(A) either way.
  test::SyntheticAvatarOptions o;
  o.handles = 0;
  const Avatar a = test::make_synthetic_avatar(o);
  const Vec3 dir(0.013, -0.021, 0.008);
  Mat3 A = Mat3::Zero();
  A.col(1) = dir;
  VecX z = VecX::Zero(a.num_reduced());
  for (int n = 0; n < a.tet.num_nodes(); ++n)
    for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(a.W, n); it; ++it)
      z.segment<3>(3 * it.col()) = a.tet.nodes(n, 1) * dir;
  const Eigen::Map<const Vec9> h(A.data());
  double expected = 0;
  for (int t = 0; t < a.tet.num_elements(); ++t) expected += 0.5 * tet_volume(a, t) * h.dot(material_H(a, t) * h);
  for (bool mean : {false, true}) {
    const MatX K = linearized_stiffness(a, material_tet_stiffness(a), mean, 0.0);
    EXPECT_NEAR(0.5 * z.dot(K * z), expected, 1e-9 * expected) << "mean_dilatation = " << mean;
  }
}

TEST(LinearizedStiffness, IsotropicVolumeEnergyOnlyFallsWithTheMean) {
  // Isotropic H = 2μ I_sym + λ v vᵀ: the deviatoric part is unchanged and the
  // volumetric one becomes Σ_c λ/2 V_c θ_c² ≤ Σ_t λ/2 V_t (tr ∇u_t)² (Jensen).
  test::SyntheticAvatarOptions o = hat_handles();
  o.rotated_frames = false;
  Avatar a = test::make_synthetic_avatar(o);
  for (RegionMaterial& m : a.materials) m.young_through = m.young_around = m.young_along;
  const MatX K = linearized_stiffness(a, material_tet_stiffness(a), true, 0.0);
  const MatX K_plain = linearized_stiffness(a, material_tet_stiffness(a), false);
  std::mt19937 rng(7);
  std::normal_distribution<double> N(0, 0.01);
  int strictly = 0;
  for (int trial = 0; trial < 20; ++trial) {
    VecX z(a.num_reduced());
    for (int i = 0; i < z.size(); ++i) z[i] = N(rng);
    const double e = z.dot(K * z), e_plain = z.dot(K_plain * z);
    EXPECT_LE(e, e_plain * (1 + 1e-12));
    EXPECT_GT(e, 0.0);
    strictly += e < e_plain * (1 - 1e-6);
  }
  EXPECT_EQ(strictly, 20);
  // Symmetric positive semi-definite.
  EXPECT_LE((K - K.transpose()).norm(), 1e-12 * K.norm());
  EXPECT_GE(Eigen::SelfAdjointEigenSolver<MatX>(K).eigenvalues().minCoeff(), -1e-9 * K.norm());
}

TEST(LinearizedStiffness, TheElasticTermsHessianAtRestIsIt) {
  const Avatar a = test::make_synthetic_avatar(hat_handles());
  StepContext ctx;
  ctx.avatar = &a;
  ctx.layout.bones_dynamic = false;
  ctx.layout.num_reduced = a.num_reduced();
  Configuration rest;
  rest.bones = std::vector<Isometry>(24, Isometry::Identity());
  rest.z = VecX::Zero(a.num_reduced());
  for (bool mean : {false, true}) {
    const ElasticTerm term(a, true, true, mean);
    EXPECT_EQ(term.mean_dilatation(), mean);
    VecX g = VecX::Zero(a.num_reduced());
    MatX H = MatX::Zero(a.num_reduced(), a.num_reduced());
    term.evaluate(ctx, rest, &g, &H);
    const MatX K = linearized_stiffness(a, material_tet_stiffness(a), mean);
    EXPECT_LE((H - K).norm(), 1e-9 * K.norm()) << "mean_dilatation = " << mean;
  }
}

}  // namespace
}  // namespace sflsh
