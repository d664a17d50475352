#pragma once
// Mass-fitted inertia cubature: a few hundred node samples whose weights are
// fitted so that the reduced model's mass matrix at rest equals the full-FEM
// reference's lumped one projected onto the model's kinematics.
//
// A body point moves as x = Σ_b w_b G_b (x̄ + Σ_k W_k z_k) (PosedPoints). At
// rest (G_b = I) its velocity is linear in the bones' translations and
// rotations and in ż, with coefficients built from the scalar fields
//   φ ∈ { W_k (k < K, Simulated nodes only),  w_b,  w_b (x̄ − c_b)_i (i < 3) },
// c_b the mass centroid of bone b's weight. Any kinetic energy of that motion
// is therefore a linear combination of the moments M_ab = Σ_n m_n φ_a φ_b over
// the lumped nodal masses m_n of every node (the reference's mass model,
// nodal_cubature; nodes that only bones move count towards the bones' moments
// as the data-oblivious cubature's samples over the whole volume did). A cubature of node samples s with masses c_s ≥ 0 reproduces the
// reduced mass matrix exactly iff Σ_s c_s φ_a(s) φ_b(s) = M_ab for every pair.
// Candidates are up to `samples_per_cell` nodes per cell (a node's cell: its
// largest handle weight, or its dominant bone where the bone complement
// 1 − Σ_k W_k is larger), spread by farthest-point sampling; c is the
// non-negative least-squares fit of the moment equations (each pair's row
// normalized by √(M_aa M_bb)) plus the total mass. Samples whose mass ends at 0
// are dropped.
//
// Why: the data-oblivious cubature (one sample per handle at the handle, where
// W_k = 1 and the other weights vanish) lumps the reduced mass onto its
// diagonal. Once the elastic energy is free of volumetric locking (mean
// dilatation), that lumping is what separates the simulation from the
// subspace's floor on inertia-driven motion (measured on `shake`).
#include <Eigen/Sparse>

#include "sflsh/asset/avatar.hpp"
#include "sflsh/core/types.hpp"
#include "sflsh/mesh/tet_mesh.hpp"

namespace sflsh::basis {

struct MassFitReport {
  int candidates = 0, samples = 0, sweeps = 0, moments = 0;
  /// ‖Σ_s c_s φφᵀ − M‖ / ‖M‖ over the normalized moment rows, with the
  /// candidates' initial masses (cell mass / samples) and with the fitted ones.
  double moment_error_initial = 0, moment_error = 0;
  double mass = 0;        ///< Σ_n m_n (kg): the mass the samples represent
  double mass_error = 0;  ///< (Σ_s c_s − mass) / mass
};

/// `W` (#N by #K): the basis; `node_role` (#N): W counts only at Simulated
/// nodes; `node_weights` (#N by #B): skinning weights; `tet_density` (#T,
/// kg/m^3). Samples sit at nodes (barycentric 1 at the node in its first tet),
/// weight = fitted mass / ρ of that tet (m^3), like nodal_cubature's, so
/// cubature_masses gives back the fitted masses. `samples_per_cell` ≥ 1.
Cubature mass_fitted_cubature(const TetMesh& mesh, const Eigen::SparseMatrix<double, Eigen::RowMajor>& W,
                              const VecXi& node_role, const MatXr& node_weights, const VecX& tet_density,
                              int samples_per_cell, MassFitReport* report = nullptr);

}  // namespace sflsh::basis
