#pragma once
// Data-oblivious cubature of the reduced model (Tapia et al. 2021; seed §4):
// a scalar field interpolated by the basis, f ≈ Σ_k W_k f_k + w_bone f_bone,
// is integrated exactly when each sample's weight is the integral of its
// weight field, c_k = ∫ W_k dV. The same samples can serve the elastic and the
// inertial integrals (Avatar::elastic and Avatar::inertia may hold copies):
// the method needs no training data for either. Precompute now
// refits both, still without training data: elasticity to the basis'
// stiffness (stiffness_fitted_cubature.hpp), inertia to the lumped mass
// matrix (mass_fitted_cubature.hpp).
#include <Eigen/Sparse>

#include "sflsh/asset/avatar.hpp"
#include "sflsh/core/types.hpp"
#include "sflsh/mesh/tet_mesh.hpp"

namespace sflsh::basis {

/// Builds the data-oblivious cubature for the basis W (#N by #K, bounded
/// biharmonic weights) of the handles at `handle_nodes` (#K).
///
/// Samples 0..K−1: handle k, in the largest tet incident to its node, at that
/// node (barycentric coordinate 1 there); weight ∫ W_k dV (m^3), exact for the
/// P1 field: Σ_e V_e · mean of W_k over e's nodes.
/// Then one sample per bone region b (the values ≥ 0 of `dominant_bone`, #N
/// per-node dominant bone index; empty = one region): weight
/// ∫ w_bone·[dominant_bone = b] dV with w_bone = 1 − Σ_k W_k (the bone
/// handle's complement weight), placed at the centroid of the tet where that
/// field's mean is largest. Regions whose weight is 0 get no sample.
/// Because Σ_k W_k + w_bone = 1, all weights sum to the mesh volume exactly,
/// so constant fields (volume, uniform-density mass) integrate exactly.
Cubature data_oblivious_cubature(const TetMesh& mesh, const Eigen::SparseMatrix<double, Eigen::RowMajor>& W,
                                 const VecXi& handle_nodes, const VecXi& dominant_bone = VecXi());

/// Positions (#S by 3, m) of the cubature samples.
Points cubature_points(const TetMesh& mesh, const Cubature& cubature);

/// Stratified cubature for the elastic energy: the volume is partitioned into
/// cells by each tet's dominant weight (a handle k, or the bone complement
/// 1 − Σ_k W_k split by `dominant_bone` of the tet's first node), and each
/// cell is represented by up to `samples_per_cell` of its tets, spread out
/// (farthest-point on centroids, deterministic), at their centroids, each
/// weighted cell volume / samples. Integrates constants exactly.
/// Why: the data-oblivious samples sit at the handles, where a biharmonic
/// weight peaks and its gradient is nearly zero, so the strain of z_k is hardly
/// seen there; with few handles the sampled elastic energy then has near-null
/// modes along which gravity makes the tissue drift (measured: free fall of the
/// soft tissue at K = 8..32). Sampling where the strain lives removes them.
Cubature stratified_cubature(const TetMesh& mesh, const Eigen::SparseMatrix<double, Eigen::RowMajor>& W,
                             const VecXi& dominant_bone, int samples_per_cell = 3);

/// Full integration: one sample per tet at its centroid, weight its volume.
/// Exact for the elastic energy (F is constant per tet); the benchmark's
/// error floor of the basis alone. Tets whose nodes are all Dirichlet
/// (`node_role` != Simulated; empty = keep all) are skipped when `simulated_only`.
Cubature full_cubature(const TetMesh& mesh, const VecXi& node_role = VecXi(), bool simulated_only = false);

/// Lumped nodal integration, the full-FEM reference's mass model: one sample
/// at each node n that lies in a tet with a Simulated node (all nodes when
/// `node_role` is empty), placed in the first tet e₀ containing n with
/// barycentric coordinate 1 at n, weight (Σ_{e∋n} ρ_e V_e / 4) / ρ_{e₀} (m^3), so that
/// ρ_{e₀}·weight is the node's lumped mass m_n. `tet_density` #T (kg/m^3;
/// empty = uniform). As the inertia cubature it makes the reduced kinetic
/// energy Σ_n m_n/2 |ẋ_n|² exactly the reference's projected onto the basis.
Cubature nodal_cubature(const TetMesh& mesh, const VecX& tet_density = VecX(), const VecXi& node_role = VecXi());

/// Cubature against full integration over all tets (relative errors are
/// (cubature − full) / full).
struct CubatureErrors {
  double volume_full = 0, volume_cubature = 0, volume_error = 0;  ///< m^3
  double mass_full = 0, mass_cubature = 0, mass_error = 0;        ///< kg
  /// f(x) = |x − c|², c the volume centroid of the mesh: m^5.
  double quadratic_full = 0, quadratic_cubature = 0, quadratic_error = 0;
};

/// Measures `cubature` on volume, mass (per-tet density `tet_density` #T in
/// kg/m^3; empty = 1000 everywhere) and the quadratic test field, each against
/// the exact integral over all tets (the quadratic one by the tet second-moment
/// formula ∫_e |x − c|² = V_e(|g_e − c|² + Σ_a |x_a − g_e|²/20), g_e the centroid).
/// The density of a sample is that of its tet.
CubatureErrors cubature_errors(const TetMesh& mesh, const Cubature& cubature, const VecX& tet_density = VecX());

}  // namespace sflsh::basis
