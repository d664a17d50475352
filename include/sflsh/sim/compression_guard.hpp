#pragma once
// A per-sample volume guard for the mean-dilatation elastic term.
//
// With mean dilatation (linearized_stiffness.hpp) the exact quadratic ½ zᵀ K z keeps only a
// share α of each tet's own bulk stiffness; the rest is averaged over the tet's cell. The
// cubature samples carry Ψ − Ψ₂, which removes each sample's full quadratic bulk term, and the
// StVK part of Ψ softens under compression (its energy stays finite as det F → 0) while the
// material's barrier is only third order in 1 − J. So a sample could lose volume while its
// cell kept its mean, and nothing pushed back until the barrier's −log J: a 10⁴-step torture
// run at dt = 1/30 drove a sample to det F = 0.000 (README, "What the gap was").
//
// The guard gives back the averaged share (1 − α) of the bulk modulus κ, but only beyond an
// onset J₀ of compression, so small strains (where mean dilatation removes the locking) are
// untouched:
//   G(J) = ½ (1 − α) κ (J₀ − J)²  for J < J₀,   0 for J ≥ J₀       (C¹; G'' jumps at J₀)
// ∂G/∂F = G'(J) cof F,  ∂²G/∂F² = G'' cof ⊗ cof + G' ∂²J/∂F²  (G' ≤ 0), and the projected
// Hessian adds |G'| √2 ‖F‖_F I, the bound the material's barrier uses (material.hpp).
#include "sflsh/sim/material.hpp"  // Mat9

namespace sflsh {

/// Onset J₀ of the guard: det F below it (8 % volume loss) is resisted per sample.
constexpr double kCompressionGuardOnset = 0.92;

/// G(det F) for a sample of bulk stiffness `stiffness` (Pa, (1 − α) κ); adds ∂G/∂F to
/// `dG_dF` and ∂²G/∂F² (9x9 over vec F, PSD-bounded when `project_psd`) to `d2G_dF2` when
/// given. Zero (and nothing added) for det F ≥ `onset`.
double compression_guard(const Mat3& F, double stiffness, double onset, Mat3* dG_dF, Mat9* d2G_dF2,
                         bool project_psd);

}  // namespace sflsh
