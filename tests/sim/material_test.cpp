// Strain energy density: gradient/Hessian vs central finite differences,
// isotropic limit, barrier behaviour, PSD projection.
#include <cmath>
#include <random>

#include <Eigen/Eigenvalues>
#include <gtest/gtest.h>

#include "sflsh/sim/material.hpp"

namespace sflsh {
namespace {

RegionMaterial test_material() {
  RegionMaterial m;
  m.name = "test";
  m.young_along = 3e4;
  m.young_through = 1e4;
  m.young_around = 2e4;
  m.poisson = 0.45;
  m.fung_c = 2e4;
  return m;
}

Mat3 random_rotation(std::mt19937& rng) {
  std::normal_distribution<double> n;
  Eigen::Quaterniond q(n(rng), n(rng), n(rng), n(rng));
  return q.normalized().toRotationMatrix();
}

Mat3 random_F(std::mt19937& rng, double spread) {
  std::uniform_real_distribution<double> u(-spread, spread);
  Mat3 F = Mat3::Identity();
  for (int i = 0; i < 9; ++i) F.data()[i] += u(rng);
  if (F.determinant() < 0.2) F = Mat3::Identity() + 0.5 * (F - Mat3::Identity());
  return F;
}

TEST(Material, GradientAndHessianMatchFiniteDifferences) {
  std::mt19937 rng(7);
  const RegionMaterial m = test_material();
  for (double spread : {0.02, 0.3}) {  // near and far from identity
    for (int trial = 0; trial < 6; ++trial) {
      const Mat3 R = random_rotation(rng);
      const Mat3 F = random_F(rng, spread);
      ASSERT_GT(F.determinant(), 0);
      Mat3 P;
      Mat9 H;
      strain_energy_density(F, R, m, &P, &H, false);
      const double eps = 1e-6;
      Vec9 P_fd;
      Mat9 H_fd;
      for (int i = 0; i < 9; ++i) {
        Mat3 Fp = F, Fm = F;
        Fp.data()[i] += eps;
        Fm.data()[i] -= eps;
        Mat3 Pp, Pm;
        P_fd[i] = (strain_energy_density(Fp, R, m, &Pp) - strain_energy_density(Fm, R, m, &Pm)) / (2 * eps);
        H_fd.col(i) = (Eigen::Map<Vec9>(Pp.data()) - Eigen::Map<Vec9>(Pm.data())) / (2 * eps);
      }
      const Vec9 Pv = Eigen::Map<Vec9>(P.data());
      EXPECT_LT((Pv - P_fd).norm(), 1e-6 * Pv.norm() + 1e-9) << "spread " << spread << " trial " << trial;
      EXPECT_LT((H - H_fd).norm(), 1e-5 * H.norm()) << "spread " << spread << " trial " << trial;
      EXPECT_LT((H - H.transpose()).norm(), 1e-12 * H.norm());
    }
  }
}

TEST(Material, RestIsStressFreeAndIsotropicLimitIsStVK) {
  RegionMaterial m = test_material();
  Mat3 P;
  Mat9 H;
  EXPECT_EQ(strain_energy_density(Mat3::Identity(), Mat3::Identity(), m, &P, &H), 0.0);
  EXPECT_LT(P.norm(), 1e-12);
  // Isotropic moduli, huge Fung scale: small strain energy ≈ μ E:E + λ/2 tr(E)²,
  // and the barrier is zero for J ≥ 1.
  m.young_along = m.young_through = m.young_around = 1e4;
  m.fung_c = 1e12;
  const double E = 1e4, nu = m.poisson, mu = E / (2 * (1 + nu)), lambda = E * nu / ((1 + nu) * (1 - 2 * nu));
  Mat3 F;
  F << 1.05, 0.02, 0.0, 0.01, 1.02, 0.03, 0.0, 0.01, 1.04;  // J > 1
  ASSERT_GT(F.determinant(), 1.0);
  const Mat3 Es = 0.5 * (F.transpose() * F - Mat3::Identity());
  const double stvk = mu * (Es.array() * Es.array()).sum() + 0.5 * lambda * Es.trace() * Es.trace();
  std::mt19937 rng(3);
  EXPECT_NEAR(strain_energy_density(F, random_rotation(rng), m), stvk, 1e-6 * stvk);
}

TEST(Material, OrthotropicStiffnessFollowsTheFrame) {
  // Stretch 1% along each local axis: energy ≈ ½ C_ii ε², C_ii ∝ E_i.
  const RegionMaterial m = test_material();
  std::mt19937 rng(11);
  const Mat3 R = random_rotation(rng);
  double psi[3];
  for (int i = 0; i < 3; ++i) {
    const Vec3 axis = R.row(i).transpose();
    const Mat3 F = Mat3::Identity() + 0.01 * axis * axis.transpose();
    psi[i] = strain_energy_density(F, R, m);
  }
  EXPECT_NEAR(psi[0] / psi[1], m.young_along / m.young_through, 0.02 * m.young_along / m.young_through);
  EXPECT_NEAR(psi[2] / psi[1], m.young_around / m.young_through, 0.02 * m.young_around / m.young_through);
}

TEST(Material, BarrierPreventsCollapseAndInversion) {
  const RegionMaterial m = test_material();
  // Uniform compression: energy grows without bound as J → 0 and is +inf when inverted.
  double previous = 0;
  for (double s : {0.9, 0.7, 0.5, 0.3, 0.1, 0.03}) {
    const double psi = strain_energy_density(s * Mat3::Identity(), Mat3::Identity(), m);
    EXPECT_GT(psi, previous) << "scale " << s;
    previous = psi;
  }
  EXPECT_GT(previous, 1e4 * 3.0);  // well above the stretch energy scale
  EXPECT_TRUE(std::isinf(strain_energy_density(Mat3(Vec3(1, 1, -1).asDiagonal()), Mat3::Identity(), m)));
  // Uniaxial compression: the restoring stress keeps pushing back (StVK alone loses it past ~42%).
  for (double s : {0.5, 0.3, 0.1}) {
    Mat3 F = Mat3::Identity();
    F(0, 0) = s;
    Mat3 P;
    strain_energy_density(F, Mat3::Identity(), m, &P);
    EXPECT_LT(P(0, 0), 0.0) << "stretch " << s;
  }
}

TEST(Material, ProjectedHessianIsPositiveSemidefinite) {
  std::mt19937 rng(5);
  const RegionMaterial m = test_material();
  int indefinite = 0;
  for (int trial = 0; trial < 20; ++trial) {
    Mat3 F = random_F(rng, 0.5);
    F(0, 0) = 0.5;  // compression makes the raw StVK Hessian indefinite
    if (F.determinant() <= 0) continue;
    Mat9 H, Hp;
    strain_energy_density(F, random_rotation(rng), m, nullptr, &H, false);
    strain_energy_density(F, random_rotation(rng), m, nullptr, &Hp, true);
    if (Eigen::SelfAdjointEigenSolver<Mat9>(H).eigenvalues().minCoeff() < 0) ++indefinite;
    EXPECT_GE(Eigen::SelfAdjointEigenSolver<Mat9>(Hp).eigenvalues().minCoeff(), -1e-9 * Hp.norm());
  }
  EXPECT_GT(indefinite, 0) << "test never exercised the projection";
}

TEST(Material, ProjectedHessianMajorizesTheExactOne) {
  std::mt19937 rng(11);
  const RegionMaterial m = test_material();
  int compressed = 0;
  for (int trial = 0; trial < 40; ++trial) {
    const Mat3 F = random_F(rng, 0.4), R = random_rotation(rng);
    if (F.determinant() <= 0) continue;
    Mat9 H, Hp;
    strain_energy_density(F, R, m, nullptr, &H, false);
    strain_energy_density(F, R, m, nullptr, &Hp, true);
    if (F.determinant() < 1) ++compressed;
    // H⁺ − H ⪰ 0: a Newton step with H⁺ is never longer along any direction.
    EXPECT_GE(Eigen::SelfAdjointEigenSolver<Mat9>(Hp - H).eigenvalues().minCoeff(), -1e-9 * H.norm()) << "trial " << trial;
  }
  EXPECT_GT(compressed, 5) << "test never exercised the barrier";
  // Stretching in every material direction (S ⪰ 0, J > 1): nothing to project.
  const Mat3 R = random_rotation(rng);
  const Mat3 F = R * Vec3(1.1, 1.2, 1.05).asDiagonal() * R.transpose();
  Mat9 H, Hp;
  strain_energy_density(F, Mat3::Identity(), m, nullptr, &H, false);
  strain_energy_density(F, Mat3::Identity(), m, nullptr, &Hp, true);
  EXPECT_LT((Hp - H).norm(), 1e-12 * H.norm());
}

}  // namespace
}  // namespace sflsh
