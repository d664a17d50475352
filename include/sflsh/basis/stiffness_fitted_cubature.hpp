#pragma once
// Stiffness-fitted elastic cubature (data-oblivious, in the spirit of An et
// al. 2008 "Optimizing cubature for efficient integration of subspace
// deformations", but fitted to the basis itself instead of training poses).
//
// With u = Σ_k W_k z_k, the displacement gradient in tet t is
// ∇u = Σ_k z_k d_{t,k}ᵀ, d_{t,k} = Σ_n W_{n,k} ∇N_n (1/m). Any elastic energy
// that is quadratic in ∇u with a per-tet constant stiffness scale E_t
// (linearized StVK of every orientation and Poisson ratio) is a linear
// combination of the entries of the tensor
//   T_{kl} = Σ_t V_t E_t d_{t,k} d_{t,l}ᵀ     (3x3 per handle pair k ≤ l).
// A cubature whose samples are whole tets s with weights c_s ≥ 0 integrates
// all of them exactly iff Σ_s c_s E_s d_{s,k} d_{s,l}ᵀ = T_{kl}. We pick
// candidate tets (stratified_cubature's, several per cell) and solve the
// non-negative least-squares problem for c (rows of each pair normalized by
// √(tr T_kk tr T_ll), plus the total volume), by projected coordinate
// descent on the normal equations. Samples whose weight ends at 0 are dropped.
// Because samples are real tets with c ≥ 0, the sampled energy keeps the
// material's large-strain behaviour (barrier, saturation) per sample.
#include <Eigen/Sparse>

#include "sflsh/asset/avatar.hpp"
#include "sflsh/core/types.hpp"
#include "sflsh/mesh/tet_mesh.hpp"

namespace sflsh::basis {

struct FittedCubatureReport {
  int candidates = 0, samples = 0, sweeps = 0;
  /// ‖Σ_s c_s E_s d d ᵀ − T‖ / ‖T‖ over the normalized pair rows, with the
  /// candidates' initial weights and with the fitted ones.
  double stiffness_error_initial = 0, stiffness_error = 0;
  double volume_error = 0;  ///< (Σ c_s − V) / V
};

/// `candidates`: tets (and their initial weights, m³) to choose from, e.g.
/// stratified_cubature(..., 6). `node_role` (#N): only Simulated nodes carry
/// W. `tet_modulus` (#T, Pa or any consistent unit; empty = 1 everywhere): the
/// stiffness scale E_t. Returns a subset of the candidates with fitted weights.
Cubature stiffness_fitted_cubature(const TetMesh& mesh, const Eigen::SparseMatrix<double, Eigen::RowMajor>& W,
                                   const VecXi& node_role, const Cubature& candidates,
                                   const VecX& tet_modulus = VecX(), FittedCubatureReport* report = nullptr);

}  // namespace sflsh::basis
