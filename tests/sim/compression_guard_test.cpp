// compression_guard: the value and stress in closed form, the Hessian against finite
// differences, the projection a PSD majorizer, and the elastic term with mean dilatation
// resisting a compression that it did not resist before the guard.
#include <random>

#include <Eigen/Eigenvalues>
#include <gtest/gtest.h>

#include "finite_difference.hpp"
#include "sflsh/sim/compression_guard.hpp"
#include "sflsh/sim/energies/elastic.hpp"
#include "sflsh/sim/linearized_stiffness.hpp"
#include "synthetic_avatar.hpp"

namespace sflsh {
namespace {

constexpr double kStiffness = 3.0e5;  // Pa

TEST(CompressionGuard, UniformCompressionInClosedForm) {
  // F = s I: J = s³, cof F = s² I, G = ½ k (J₀ − s³)², ∂G/∂F = −k (J₀ − s³) s² I.
  for (double s : {0.5, 0.9, 0.97}) {
    const Mat3 F = s * Mat3::Identity();
    Mat3 P = Mat3::Zero();
    const double G = compression_guard(F, kStiffness, 0.92, &P, nullptr, false);
    const double J = s * s * s;
    if (J >= 0.92) {
      EXPECT_EQ(G, 0.0) << s;
      EXPECT_EQ(P.norm(), 0.0) << s;
      continue;
    }
    EXPECT_NEAR(G, 0.5 * kStiffness * (0.92 - J) * (0.92 - J), 1e-9 * G) << s;
    EXPECT_LT((P - (-kStiffness * (0.92 - J) * s * s) * Mat3::Identity()).norm(), 1e-9 * P.norm()) << s;
  }
  // Uniaxial: F = diag(0.7, 1, 1), J = 0.7, cof = diag(1, 0.7, 0.7).
  Mat3 P = Mat3::Zero();
  const double G = compression_guard(Vec3(0.7, 1, 1).asDiagonal(), kStiffness, 0.92, &P, nullptr, false);
  EXPECT_NEAR(G, 0.5 * kStiffness * 0.22 * 0.22, 1e-6);
  EXPECT_NEAR(P(0, 0), -kStiffness * 0.22 * 1.0, 1e-6);
  EXPECT_NEAR(P(1, 1), -kStiffness * 0.22 * 0.7, 1e-6);
  EXPECT_NEAR(P(0, 1), 0.0, 1e-9);
}

TEST(CompressionGuard, HessianMatchesFiniteDifferencesAndItsProjectionMajorizesIt) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-0.15, 0.15);
  int active = 0;
  for (int trial = 0; trial < 20; ++trial) {
    Mat3 F = 0.85 * Mat3::Identity();
    for (int i = 0; i < 9; ++i) F.data()[i] += u(rng);
    if (!(F.determinant() < 0.9 && F.determinant() > 0.1)) continue;
    ++active;
    Mat3 P = Mat3::Zero();
    Mat9 H = Mat9::Zero(), Hp = Mat9::Zero();
    compression_guard(F, kStiffness, 0.92, &P, &H, false);
    compression_guard(F, kStiffness, 0.92, nullptr, &Hp, true);
    const double eps = 1e-6;
    for (int i = 0; i < 9; ++i) {
      Mat3 Fp = F, Fm = F;
      Fp.data()[i] += eps;
      Fm.data()[i] -= eps;
      const double g_fd = (compression_guard(Fp, kStiffness, 0.92, nullptr, nullptr, false) -
                           compression_guard(Fm, kStiffness, 0.92, nullptr, nullptr, false)) /
                          (2 * eps);
      EXPECT_NEAR(P.data()[i], g_fd, 1e-6 * P.norm());
      Mat3 Pp = Mat3::Zero(), Pm = Mat3::Zero();
      compression_guard(Fp, kStiffness, 0.92, &Pp, nullptr, false);
      compression_guard(Fm, kStiffness, 0.92, &Pm, nullptr, false);
      const Mat3 col = (Pp - Pm) / (2 * eps);
      EXPECT_LT((H.col(i) - Eigen::Map<const Vec9>(col.data())).norm(), 1e-5 * H.norm()) << "column " << i;
    }
    EXPECT_GE(Eigen::SelfAdjointEigenSolver<Mat9>(Hp).eigenvalues().minCoeff(), -1e-9 * Hp.norm());
    EXPECT_GE(Eigen::SelfAdjointEigenSolver<Mat9>(Hp - H).eigenvalues().minCoeff(), -1e-9 * Hp.norm());
  }
  EXPECT_GE(active, 10);
}

TEST(CompressionGuard, MeanDilatationTermMatchesFiniteDifferencesUnderStrongCompression) {
  test::SyntheticAvatarOptions o;
  o.nx = 1, o.ny = 2, o.nz = 1;
  o.handles = 5;
  const Avatar a = test::make_synthetic_avatar(o);
  const ElasticTerm term(a, /*project_psd=*/false, /*exact_quadratic=*/true, /*mean_dilatation=*/true);
  const StepContext ctx = test::soft_step_context(a, false);
  // Squeeze every handle towards the slab's centre: the samples lose 20-40 % of their volume.
  Vec3 centre = a.handles.colwise().mean().transpose();
  Configuration q;
  q.bones = std::vector<Isometry>(24, Isometry::Identity());
  q.z = VecX(a.num_reduced());
  for (int k = 0; k < a.num_handles(); ++k) q.z.segment<3>(3 * k) = -0.15 * (a.handles.row(k).transpose() - centre);
  ASSERT_LT(term.min_det(q.z), kCompressionGuardOnset);
  ASSERT_GT(term.min_det(q.z), 0.2);
  const auto d = test::analytic(term, ctx, q);
  const VecX g_fd = test::fd_gradient(term, ctx, q, 1e-8);
  EXPECT_LT((d.grad - g_fd).norm(), 1e-6 * d.grad.norm());
  std::mt19937 rng(5);
  EXPECT_LT(test::hessian_fd_error(term, ctx, q, d.hess, 1e-6, 8, rng), 1e-5);
}

}  // namespace
}  // namespace sflsh
