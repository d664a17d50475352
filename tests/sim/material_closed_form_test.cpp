// The material law against values computed by hand from the formulas that
// include/sflsh/sim/material.hpp and src/sim/material.cpp document (local
// axes 0 = along, 1 = through, 2 = around; one Poisson ratio ν):
//   C_ij = √(E_i E_j)/(1+ν) (δ_ij + ν/(1−2ν)),   G_ij = √(E_i E_j)/(2(1+ν)),
//   Ψ_stvk = ½ Σ_ij C_ij Ẽ_ii Ẽ_jj + 2 Σ_{i<j} G_ij Ẽ_ij²,   Ẽ = R E Rᵀ,
//   Ψ = (c/2)(exp(2Ψ_stvk/c) − 1) + Ψ_vol(J),
//   Ψ_vol = κ(−log J + (J−1) − ½(J−1)²) for J < 1, κ = Ē/(3(1−2ν)), Ē = (E_0 E_1 E_2)^{1/3},
//   P = exp(2Ψ_stvk/c) F S + Ψ_vol'(J) J F⁻ᵀ.
// Unlike the finite-difference tests, these see a wrong constant whose value
// and derivative stay consistent (a κ three times too big, a swapped modulus).
#include <cmath>

#include <gtest/gtest.h>

#include "sflsh/sim/material.hpp"

namespace sflsh {
namespace {

RegionMaterial hand_material() {
  RegionMaterial m;
  m.name = "hand";
  m.young_along = 3e4;
  m.young_through = 1e4;
  m.young_around = 2e4;
  m.poisson = 0.45;
  m.fung_c = 2e3;
  return m;
}

double E_axis(const RegionMaterial& m, int i) { return i == 0 ? m.young_along : i == 1 ? m.young_through : m.young_around; }
double C_hand(const RegionMaterial& m, int i, int j) {
  const double nu = m.poisson;
  return std::sqrt(E_axis(m, i) * E_axis(m, j)) / (1 + nu) * ((i == j ? 1.0 : 0.0) + nu / (1 - 2 * nu));
}
double G_hand(const RegionMaterial& m, int i, int j) {
  return std::sqrt(E_axis(m, i) * E_axis(m, j)) / (2 * (1 + m.poisson));
}
double kappa_hand(const RegionMaterial& m) {
  return std::cbrt(m.young_along * m.young_through * m.young_around) / (3 * (1 - 2 * m.poisson));
}
double fung(const RegionMaterial& m, double psi_stvk) { return 0.5 * m.fung_c * (std::exp(2 * psi_stvk / m.fung_c) - 1); }
double fung_slope(const RegionMaterial& m, double psi_stvk) { return std::exp(2 * psi_stvk / m.fung_c); }

void expect_rel(double got, double want, double rel, const char* what) {
  EXPECT_NEAR(got, want, rel * std::abs(want)) << what;
}
void expect_matrix(const Mat3& got, const Mat3& want, double rel) {
  EXPECT_LE((got - want).norm(), rel * want.norm()) << "got\n" << got << "\nwant\n" << want;
}

TEST(MaterialClosedForm, UniaxialStretchAlongEachLocalAxis) {
  const RegionMaterial m = hand_material();
  const double lambda = 1.2, e = 0.5 * (lambda * lambda - 1);  // E_aa; J = λ > 1: no barrier
  for (int a = 0; a < 3; ++a) {
    SCOPED_TRACE(a);
    Mat3 F = Mat3::Identity();
    F(a, a) = lambda;
    const double psi_s = 0.5 * C_hand(m, a, a) * e * e;
    Mat3 S = Mat3::Zero();  // S_ii = Σ_j C_ij E_jj = C_ia e
    for (int i = 0; i < 3; ++i) S(i, i) = C_hand(m, i, a) * e;
    const Mat3 P_hand = fung_slope(m, psi_s) * F * S;
    Mat3 P;
    expect_rel(strain_energy_density(F, Mat3::Identity(), m, &P), fung(m, psi_s), 1e-12, "psi");
    expect_matrix(P, P_hand, 1e-12);
  }
}

TEST(MaterialClosedForm, SimpleShearInEachPlane) {
  const RegionMaterial m = hand_material();
  const double g = 0.3;
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b) {
      if (a == b) continue;
      SCOPED_TRACE(std::to_string(a) + "," + std::to_string(b));
      Mat3 F = Mat3::Identity();
      F(a, b) = g;  // x_a += γ X_b, J = 1: no barrier
      // E = ½(FᵀF − I): E_ab = E_ba = γ/2, E_bb = γ²/2.
      const double Eab = g / 2, Ebb = g * g / 2;
      const double psi_s = 0.5 * C_hand(m, b, b) * Ebb * Ebb + 2 * G_hand(m, a, b) * Eab * Eab;
      Mat3 S = Mat3::Zero();
      for (int i = 0; i < 3; ++i) S(i, i) = C_hand(m, i, b) * Ebb;
      S(a, b) = S(b, a) = 2 * G_hand(m, a, b) * Eab;
      Mat3 P;
      expect_rel(strain_energy_density(F, Mat3::Identity(), m, &P), fung(m, psi_s), 1e-12, "psi");
      expect_matrix(P, fung_slope(m, psi_s) * F * S, 1e-12);
    }
}

TEST(MaterialClosedForm, UniformCompressionIncludingTheBarrier) {
  const RegionMaterial m = hand_material();
  const double kappa = kappa_hand(m);
  for (double s : {0.97, 0.95, 0.9}) {
    SCOPED_TRACE(s);
    const Mat3 F = s * Mat3::Identity();
    const double J = s * s * s, e = 0.5 * (s * s - 1);
    double sumC = 0;
    Mat3 S = Mat3::Zero();
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) {
        sumC += C_hand(m, i, j);
        S(i, i) += C_hand(m, i, j) * e;
      }
    const double psi_s = 0.5 * sumC * e * e;
    const double psi_vol = kappa * (-std::log(J) + (J - 1) - 0.5 * (J - 1) * (J - 1));
    const double dvol = kappa * (-1 / J + 1 - (J - 1));
    const Mat3 P_hand = fung_slope(m, psi_s) * F * S + dvol * J * F.inverse().transpose();
    Mat3 P;
    const double psi = strain_energy_density(F, Mat3::Identity(), m, &P);
    expect_rel(psi, fung(m, psi_s) + psi_vol, 1e-12, "psi");
    // The barrier on its own, so that its share cannot hide in the total.
    expect_rel(psi - fung(m, psi_s), psi_vol, 1e-8, "barrier");
    expect_matrix(P, P_hand, 1e-12);
    EXPECT_GT(psi_vol, 0.02 * psi) << "the barrier must carry a visible share at this compression";
  }
  // The stored constant itself.
  EXPECT_NEAR(MaterialPoint(m, Mat3::Identity()).kappa, kappa, 1e-9 * kappa);
  EXPECT_NEAR(kappa, std::cbrt(3e4 * 1e4 * 2e4) / 0.3, 1e-9 * kappa);
}

TEST(MaterialClosedForm, FrameRowsNameAlongThroughAround) {
  // Frame rows: along = global z, through = global x, around = global y.
  const RegionMaterial m = hand_material();
  Mat3 R;
  R << 0, 0, 1, 1, 0, 0, 0, 1, 0;
  const double lambda = 1.1, e = 0.5 * (lambda * lambda - 1);
  const int global_of_local[3] = {2, 0, 1};
  for (int local = 0; local < 3; ++local) {
    Mat3 F = Mat3::Identity();
    F(global_of_local[local], global_of_local[local]) = lambda;
    expect_rel(strain_energy_density(F, R, m), fung(m, 0.5 * C_hand(m, local, local) * e * e), 1e-12,
               local == 0 ? "along" : local == 1 ? "through" : "around");
  }
}

}  // namespace
}  // namespace sflsh
