#pragma once
// Soft-tissue constitutive model (DESIGN.md §4; Romero et al. 2020 style):
// orthotropic Saint Venant–Kirchhoff in a local frame (rows of `frame`:
// along the bone, through the thickness, around the limb), with Fung-type
// exponential saturation Ψ = (c/2)(exp(2 Ψ_stvk / c) − 1), plus a volume term
// that keeps elements from collapsing or inverting under compression.
#include <Eigen/Core>

#include "sflsh/asset/avatar.hpp"
#include "sflsh/core/types.hpp"

namespace sflsh {

using Mat9 = Eigen::Matrix<double, 9, 9>;
using Vec9 = Eigen::Matrix<double, 9, 1>;
using Mat6 = Eigen::Matrix<double, 6, 6>;
using Vec6 = Eigen::Matrix<double, 6, 1>;

/// One place's material with everything that does not depend on F computed
/// once: the orthotropic stiffness rotated into the unposed space, as 6x6 over
/// the Voigt strain e = (E00, E11, E22, E01, E02, E12) (Ψ_stvk = ½ eᵀ C e, so
/// the shear rows carry the factor 2 of E01 = E10), the Fung constant c and
/// the barrier's bulk modulus κ. Throws on an invalid material (naming it).
struct MaterialPoint {
  MaterialPoint(const RegionMaterial& material, const Mat3& frame);
  Mat6 stiffness;       ///< Pa, material space
  double fung_c = 0;    ///< Pa
  double kappa = 0;     ///< Pa, compression-barrier modulus
};

/// Strain energy density Ψ(F) (J/m^3) for deformation gradient F (3x3) and
/// local frame R (3x3, orthonormal rows). If `dPsi_dF` is given it receives
/// ∂Ψ/∂F (first Piola–Kirchhoff stress, 3x3); if `d2Psi_dF2` is given it
/// receives ∂²Ψ/∂F² as 9x9 over vec(F) in column-major order (F(0,0), F(1,0),
/// F(2,0), F(0,1), ...), projected to positive semi-definite when
/// `project_psd` is true. The projection is analytic and a majorizer, H⁺ ⪰ H
/// (H⁺ − H is PSD), so a Newton step with it never overshoots:
///   H   = φ'(S ⊗ I + Bᵀ C B) + φ'' g gᵀ + Ψ_vol'' ∇J ∇Jᵀ + Ψ_vol' ∂²J/∂F²,
///   H⁺ = φ'([S]₊ ⊗ I + Bᵀ C B) + φ'' g gᵀ + Ψ_vol'' ∇J ∇Jᵀ + Ψ_vol' ∂²J/∂F² + |Ψ_vol'| √2 ‖F‖ I,
/// with [S]₊ the 2nd Piola–Kirchhoff stress with negative eigenvalues set to
/// 0 (3x3, closed form) and √2 ‖F‖_F a bound on the spectral radius of
/// ∂²J/∂F². The only non-PSD pieces of H are S ⊗ I under compression and the
/// barrier's Ψ_vol' ∂²J/∂F² (Ψ_vol' ≤ 0, second order in 1 − J), so H⁺ = H in
/// tension. This costs a 3x3 eigensolve instead of a 9x9 one.
double strain_energy_density(const Mat3& F, const MaterialPoint& material, Mat3* dPsi_dF = nullptr,
                             Mat9* d2Psi_dF2 = nullptr, bool project_psd = false);
/// ∂²Ψ/∂F² at F = I (9x9, constant): the Hessian of the linearized energy
/// Ψ₂(F) = ½ vec(F − I)ᵀ H₂ vec(F − I) (small-strain orthotropic elasticity;
/// Fung saturation and the barrier have no second-order term at F = I).
Mat9 linearized_hessian(const MaterialPoint& material);

/// ∂(det F)/∂F = cofactor(F): columns f1 × f2, f2 × f0, f0 × f1.
Mat3 determinant_gradient(const Mat3& F);
/// ∂²(det F)/∂F² as 9x9 over vec(F) (column-major; 3x3 blocks over the columns
/// of F: ±hat of the third column). Indefinite, spectral radius ≤ √2 ‖F‖_F.
Mat9 determinant_hessian(const Mat3& F);
/// The same for a material and frame given separately (builds the MaterialPoint).
double strain_energy_density(const Mat3& F, const Mat3& frame, const RegionMaterial& material,
                             Mat3* dPsi_dF = nullptr, Mat9* d2Psi_dF2 = nullptr, bool project_psd = false);

}  // namespace sflsh
