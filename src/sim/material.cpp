// Orthotropic Saint Venant–Kirchhoff with Fung saturation and a compression
// barrier (DESIGN.md §4; Romero et al. 2020, "Modeling and estimation of
// nonlinear skin mechanics for animated avatars").
//
// Ψ(F) = (c/2)(exp(2 Ψ_stvk(Ẽ)/c) − 1) + Ψ_vol(J),   Ẽ = R E Rᵀ,  E = ½(FᵀF − I).
//
// Orthotropic stiffness (local axes 1 = along, 2 = through, 3 = around; one
// Poisson ratio ν for every pair). The compliance uses the geometric-mean rule
// ν_ij / E_i = ν / √(E_i E_j), which keeps it symmetric:
//   S_normal = D^{-1/2} A D^{-1/2},  D = diag(E_1, E_2, E_3),  A = (1+ν) I − ν 11ᵀ,
// A has eigenvalues 1+ν (twice) and 1−2ν, so S (hence C = S⁻¹) is symmetric
// positive definite for −1 < ν < ½. Inverting in closed form:
//   C_ij = √(E_i E_j) / (1+ν) · (δ_ij + ν / (1 − 2ν)),
//   G_ij = √(E_i E_j) / (2(1+ν))          (shear moduli),
// which for E_1 = E_2 = E_3 is exactly isotropic StVK (C_ii = λ+2μ, C_ij = λ, G = μ).
//   Ψ_stvk = ½ Σ_ij C_ij Ẽ_ii Ẽ_jj + 2 Σ_{i<j} G_ij Ẽ_ij².
//
// Why StVK alone fails under compression: Ψ_stvk is a quartic in F that stays
// finite as the element collapses (F → 0 gives E → −I/2, a finite energy), its
// stress vanishes again past ~42% uniaxial compression (the force–stretch curve
// turns back) and it is symmetric under reflections (Ψ(F) = Ψ(−F)), so a
// compressed element can snap through and invert at no cost. Fung saturation
// only rescales Ψ_stvk and inherits this. We add a barrier that is zero up to
// second order at J = 1 (so the small-strain response is the orthotropic one
// above) and grows to +∞ as J → 0⁺:
//   Ψ_vol(J) = κ (−log J + (J − 1) − ½(J − 1)²)  for J < 1,  0 for J ≥ 1,
// with Ψ_vol''(J) = κ (1/J² − 1) ≥ 0 on (0, 1) (convex in J, C² at J = 1) and
// κ = Ē / (3(1 − 2ν)) the bulk modulus of the isotropic material with the
// geometric-mean Young's modulus Ē = (E_1 E_2 E_3)^{1/3}. Ψ = +∞ for J ≤ 0.
//
// Overflow guard: exp(x), x = 2Ψ_stvk/c, is continued beyond x_max = 40 by its
// second-order Taylor polynomial (C², convex, monotone) so extreme strains give
// huge but finite stresses instead of inf/NaN.
#include "sflsh/sim/material.hpp"

#include <cmath>
#include <limits>

#include <Eigen/Eigenvalues>

#include "sflsh/core/error.hpp"
#include "sflsh/core/rotation.hpp"

namespace sflsh {
namespace {

constexpr double kFungExponentMax = 40.0;

/// 9x9 over column-major vec (index a + 3b) of the orthotropic stiffness in the
/// local frame: vec(S̃) = C̃ vec(Ẽ) for symmetric Ẽ.
Mat9 local_stiffness(const RegionMaterial& m) {
  m.require_in_range();
  const double nu = m.poisson;
  const double E[3] = {m.young_along, m.young_through, m.young_around};
  Mat9 C = Mat9::Zero();
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      const double s = std::sqrt(E[i] * E[j]);
      if (i == j) {
        for (int k = 0; k < 3; ++k)
          C(i + 3 * i, k + 3 * k) = std::sqrt(E[i] * E[k]) / (1 + nu) * ((i == k ? 1.0 : 0.0) + nu / (1 - 2 * nu));
      } else {
        // Ψ ∋ G_ij (Ẽ_ij² + Ẽ_ji²)  ⇒  S̃_ij = 2 G_ij Ẽ_ij.
        C(i + 3 * j, i + 3 * j) = 2.0 * s / (2 * (1 + nu));
      }
    }
  return C;
}

/// Kronecker product A ⊗ B of two 3x3 matrices (9x9): vec(B X Aᵀ) = (A ⊗ B) vec(X).
Mat9 kron(const Mat3& A, const Mat3& B) {
  Mat9 K;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) K.block<3, 3>(3 * i, 3 * j) = A(i, j) * B;
  return K;
}

Eigen::Map<const Vec9> vec(const Mat3& M) { return Eigen::Map<const Vec9>(M.data()); }

/// Voigt index pairs: e_p = E(a_p, b_p).
constexpr int kVoigtA[6] = {0, 1, 2, 0, 0, 1};
constexpr int kVoigtB[6] = {0, 1, 2, 1, 2, 2};

/// [A]₊: A (symmetric 3x3) with its negative eigenvalues set to 0.
Mat3 positive_part(const Mat3& A) {
  Eigen::SelfAdjointEigenSolver<Mat3> eig;
  eig.computeDirect(A);
  if (eig.eigenvalues().minCoeff() >= 0.0) return A;
  return eig.eigenvectors() * eig.eigenvalues().cwiseMax(0.0).asDiagonal() * eig.eigenvectors().transpose();
}

}  // namespace

MaterialPoint::MaterialPoint(const RegionMaterial& m, const Mat3& frame) {
  const Mat9 RR = kron(frame, frame);                   // vec(R E Rᵀ) = (R ⊗ R) vec(E)
  const Mat9 C = RR.transpose() * local_stiffness(m) * RR;  // material space: vec(S) = C vec(E)
  // Voigt: vec(E) = M e with E01 = E10 = e_3 etc., so Ψ = ½ eᵀ (Mᵀ C M) e.
  Eigen::Matrix<double, 9, 6> M = Eigen::Matrix<double, 9, 6>::Zero();
  for (int p = 0; p < 6; ++p) {
    M(kVoigtA[p] + 3 * kVoigtB[p], p) = 1.0;
    M(kVoigtB[p] + 3 * kVoigtA[p], p) = 1.0;
  }
  stiffness = M.transpose() * C * M;
  fung_c = m.fung_c;
  const double Ebar = std::cbrt(m.young_along * m.young_through * m.young_around);
  kappa = Ebar / (3.0 * (1.0 - 2.0 * m.poisson));
}

Mat3 determinant_gradient(const Mat3& F) {
  Mat3 cof;
  cof.col(0) = F.col(1).cross(F.col(2));
  cof.col(1) = F.col(2).cross(F.col(0));
  cof.col(2) = F.col(0).cross(F.col(1));
  return cof;
}

Mat9 determinant_hessian(const Mat3& F) {
  Mat9 HJ = Mat9::Zero();
  HJ.block<3, 3>(0, 3) = -hat(F.col(2));
  HJ.block<3, 3>(0, 6) = hat(F.col(1));
  HJ.block<3, 3>(3, 0) = hat(F.col(2));
  HJ.block<3, 3>(3, 6) = -hat(F.col(0));
  HJ.block<3, 3>(6, 0) = -hat(F.col(1));
  HJ.block<3, 3>(6, 3) = hat(F.col(0));
  return HJ;
}

Mat9 linearized_hessian(const MaterialPoint& material) {
  Mat9 H;
  strain_energy_density(Mat3::Identity(), material, nullptr, &H, false);
  return H;
}

double strain_energy_density(const Mat3& F, const Mat3& frame, const RegionMaterial& material, Mat3* dPsi_dF,
                             Mat9* d2Psi_dF2, bool project_psd) {
  return strain_energy_density(F, MaterialPoint(material, frame), dPsi_dF, d2Psi_dF2, project_psd);
}

double strain_energy_density(const Mat3& F, const MaterialPoint& material, Mat3* dPsi_dF, Mat9* d2Psi_dF2,
                             bool project_psd) {
  const double J = F.determinant();
  if (!(J > 0.0)) return std::numeric_limits<double>::infinity();

  // --- orthotropic StVK, Voigt ---
  const Mat3 FtF = F.transpose() * F;
  Vec6 e;
  for (int p = 0; p < 6; ++p) e[p] = 0.5 * (FtF(kVoigtA[p], kVoigtB[p]) - (p < 3 ? 1.0 : 0.0));
  const Vec6 s6 = material.stiffness * e;  // ∂Ψ_stvk/∂e
  const double psi_stvk = 0.5 * e.dot(s6);

  // --- Fung saturation φ(Ψ_s) = (c/2)(exp(2Ψ_s/c) − 1), with the C² Taylor continuation ---
  const double c = material.fung_c;
  const double x = 2.0 * psi_stvk / c;
  double ex, dex, ddex;  // "exp" value and its first/second derivatives in x
  if (x <= kFungExponentMax) {
    ex = dex = ddex = std::exp(x);
  } else {
    const double e0 = std::exp(kFungExponentMax), d = x - kFungExponentMax;
    ex = e0 * (1 + d + 0.5 * d * d);
    dex = e0 * (1 + d);
    ddex = e0;
  }
  // expm1: at small strain x ~ 1e-6, exp(x) − 1 would keep only ~10 digits.
  const double psi_fung = 0.5 * c * (x <= kFungExponentMax ? std::expm1(x) : ex - 1.0);
  const double dphi = dex;             // dφ/dΨ_s
  const double ddphi = 2.0 * ddex / c; // d²φ/dΨ_s²

  // --- compression barrier ---
  const double kappa = material.kappa;
  double psi_vol = 0, dvol = 0, ddvol = 0;  // value, d/dJ, d²/dJ²
  if (J < 1.0) {
    psi_vol = kappa * (-std::log(J) + (J - 1) - 0.5 * (J - 1) * (J - 1));
    dvol = kappa * (-1.0 / J + 1.0 - (J - 1));
    ddvol = kappa * (1.0 / (J * J) - 1.0);
  }

  if (dPsi_dF || d2Psi_dF2) {
    // Second Piola–Kirchhoff stress: S_aa = s_p, S_ab = S_ba = s_p / 2 (E_ab appears twice in vec(E)).
    Mat3 S;
    for (int p = 0; p < 6; ++p) {
      const double v = p < 3 ? s6[p] : 0.5 * s6[p];
      S(kVoigtA[p], kVoigtB[p]) = S(kVoigtB[p], kVoigtA[p]) = v;
    }
    const Mat3 P_stvk = F * S;  // first Piola–Kirchhoff stress of StVK
    // ∂J/∂F = cofactor(F) = J F^{-T}, columns f1 × f2, f2 × f0, f0 × f1.
    const Mat3 cof = determinant_gradient(F);
    if (dPsi_dF) *dPsi_dF = dphi * P_stvk + dvol * cof;
    if (d2Psi_dF2) {
      // B = ∂e/∂vec(F) (6x9): ∂E_ab/∂f_a = ½ f_b, ∂E_ab/∂f_b = ½ f_a (f_a = column a of F).
      Eigen::Matrix<double, 6, 9> B = Eigen::Matrix<double, 6, 9>::Zero();
      for (int p = 0; p < 6; ++p) {
        const int a = kVoigtA[p], b = kVoigtB[p];
        B.block<1, 3>(p, 3 * a) += 0.5 * F.col(b).transpose();
        B.block<1, 3>(p, 3 * b) += 0.5 * F.col(a).transpose();
      }
      // ∂²Ψ_stvk/∂F² = S ⊗ I (from dF S) + Bᵀ C B (from F dS). Projected: [S]₊ ⊗ I.
      Mat9 H_stvk = B.transpose() * (material.stiffness * B);
      const Mat3 S_geometric = project_psd ? positive_part(S) : S;
      for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b) H_stvk.block<3, 3>(3 * a, 3 * b).diagonal().array() += S_geometric(a, b);
      const Mat9 HJ = determinant_hessian(F);
      const Vec9 gP = vec(P_stvk), gJ = vec(cof);
      Mat9 H = dphi * H_stvk + ddphi * gP * gP.transpose() + ddvol * gJ * gJ.transpose() + dvol * HJ;
      // dvol ≤ 0 (J + 1/J ≥ 2) and ∂²J/∂F² is indefinite with spectral radius
      // ≤ σ_a + σ_b (two largest singular values; Smith et al. 2019) ≤ √2 ‖F‖_F.
      if (project_psd && dvol < 0) H.diagonal().array() += -dvol * std::sqrt(2.0) * F.norm();
      *d2Psi_dF2 = 0.5 * (H + H.transpose());
    }
  }
  return psi_fung + psi_vol;
}

}  // namespace sflsh
