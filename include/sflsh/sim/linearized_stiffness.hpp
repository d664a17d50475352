#pragma once
// The exact small-strain stiffness of the reduced model:
//   ½ zᵀ K z = Σ_t V_t ½ vec(∇u_t)ᵀ H_t vec(∇u_t),   ∇u_t = Σ_h z_h d_{t,h}ᵀ,
// over every tet that moves, H_t = ∂²Ψ₂/∂F² of the tet's material and frame
// (material.hpp, linearized_hessian), d_{t,h} = Σ_n W_{n,h} ∇N_n.
//
// Mean dilatation ("B-bar", Hughes 1980; Simo, Taylor & Pister 1985). A smooth
// subspace of K handles cannot follow the near-isochoric motion of tissue with
// ν = 0.45 tet by tet: constraining the volume change of every one of ~40k tets
// with 3K DoFs locks it. Measured on the default body (`sflsh bench`, jump):
// the Galerkin projection of the full-FEM reference onto the basis (elastic
// on all tets, the reference's lumped masses) misses it by rel_err 0.35 while
// the basis can represent it to 0.13 (the floor). With `mean_dilatation` the
// trace of ∇u_t is replaced by its volume mean over the tet's cell, the tets
// whose largest summed handle weight is handle k:
//   ∇ū_t = ∇u_t − (tr ∇u_t / 3) I + (θ_c / 3) I,   θ_c = Σ_{s∈c} V_s tr ∇u_s / V_c,
// so each cell keeps one volume constraint (K of them for 3K DoFs) and the
// deviatoric (shape-changing) part stays exact per tet. With one tet per cell
// this is the plain assembly. K is assembled as
//   Σ_t V_t Bᵀ P H_t P B + Σ_c [(a_c g_cᵀ + g_c a_cᵀ)/3 + s_c g_c g_cᵀ / 9],
// P = I − v vᵀ/3 (v = vec I) the deviatoric projector, g_c = ∂θ_c/∂z,
// a_c = Σ_{t∈c} V_t Bᵀ P H_t v, s_c = Σ_{t∈c} V_t vᵀ H_t v.
//
// Partial average. A share α of each tet's own volume change is kept:
//   K_α = (1 − α) K_mean + α K_plain,
// i.e. the deviatoric part exact, the volumetric part (1 − α) averaged and α
// per tet. Pure averaging (α = 0) lets a tet change volume freely as long as
// its cell's mean is kept; at large strain only the sampled barrier resists,
// and a torture run on a coarse test avatar compressed a sample to det F =
// 0.08 (0.88 with every tet's own). α = 0.2 leaves a per-tet bulk modulus of
// 0.2 κ ≈ 2 μ at ν = 0.45 (below the shear stiffness's scale, so no locking)
// and keeps det F ≥ 0.88 there; on `jump` rel_err is 0.198 against 0.183 at
// α = 0 and 0.334 at α = 1, with the largest skin error 7.1 mm against 8.5
// and 9.0 mm (README, "What the gap was").
#include <functional>

#include "sflsh/asset/avatar.hpp"
#include "sflsh/core/types.hpp"
#include "sflsh/sim/material.hpp"

namespace sflsh {

/// Per tet t: writes H_t (9x9 over vec(∇u) column-major, Pa, symmetric,
/// without the volume) and returns true, or returns false to leave t out
/// (the tet still counts towards its cell's mean dilatation).
using TetStiffness = std::function<bool(int t, Mat9& H)>;

/// Cell of every tet (#T): the handle whose weight summed over the tet's four
/// nodes is largest, or −1 when no handle weights the tet (it does not move).
VecXi dilatation_cells(const Avatar& avatar);

/// The default share α of every tet's own volume change kept with mean dilatation.
constexpr double kPerTetVolumeShare = 0.2;

/// K (3K by 3K, N/m: z in m) of `avatar` for per-tet Hessians `tet_stiffness`;
/// with `mean_dilatation` the tets' volume change is averaged over
/// dilatation_cells, keeping the share `per_tet_share` (α in [0, 1]) of each
/// tet's own (see above); otherwise every tet is integrated as is.
MatX linearized_stiffness(const Avatar& avatar, const TetStiffness& tet_stiffness, bool mean_dilatation,
                          double per_tet_share = kPerTetVolumeShare);

/// The material's own H_t (linearized_hessian of tet_material and tet_frame).
TetStiffness material_tet_stiffness(const Avatar& avatar);

}  // namespace sflsh
