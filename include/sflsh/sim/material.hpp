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

/// Strain energy density Ψ(F) (J/m^3) for deformation gradient F (3x3) and
/// local frame R (3x3, orthonormal rows). If `dPsi_dF` is given it receives
/// ∂Ψ/∂F (first Piola–Kirchhoff stress, 3x3); if `d2Psi_dF2` is given it
/// receives ∂²Ψ/∂F² as 9x9 over vec(F) in column-major order (F(0,0), F(1,0),
/// F(2,0), F(0,1), ...), projected to positive semi-definite when
/// `project_psd` is true.
double strain_energy_density(const Mat3& F, const Mat3& frame, const RegionMaterial& material,
                             Mat3* dPsi_dF = nullptr, Mat9* d2Psi_dF2 = nullptr, bool project_psd = false);

}  // namespace sflsh
