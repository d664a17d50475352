#pragma once
// The lowest vibration modes of the soft tissue with the bones held (the
// second candidate basis, measured by its error floor in `sflsh bench`):
//   K φ = ω² M φ   over the Simulated nodes, every other node fixed (Dirichlet),
// K = Σ_t V_t G_tᵀ H_t G_t the small-strain stiffness at rest (H_t the tet's
// 9 by 9 material Hessian over vec(∇u), column-major; G_t maps the tet's 12
// nodal displacements to vec(∇u)), M the lumped nodal mass. Solved by
// shift-invert Lanczos (Spectra) on the symmetric M^{-1/2} K M^{-1/2} with one
// sparse Cholesky factorization of K restricted to the free nodes.
#include <functional>

#include <Eigen/Sparse>

#include "sflsh/asset/avatar.hpp"
#include "sflsh/core/types.hpp"
#include "sflsh/mesh/tet_mesh.hpp"

namespace sflsh {

/// Modes of a mass-weighted symmetric eigenproblem.
struct VibrationModes {
  MatX phi;     ///< dN by m; row di + c is component c at node i; Φᵀ M Φ = I; 0 at fixed nodes
  VecX omega2;  ///< m eigenvalues ω² (1/s²), ascending
};

/// Per tet t: writes H_t (9 by 9, Pa, over vec(∇u) column-major) and returns
/// true, or returns false to leave the tet out.
using TetHessian = std::function<bool(int t, Eigen::Matrix<double, 9, 9>& H)>;

/// 3N by 3N small-strain stiffness Σ_t V_t G_tᵀ H_t G_t (N/m), DoF 3i + c.
/// Fails naming the tet if one is degenerate or inverted.
Eigen::SparseMatrix<double> nodal_stiffness(const TetMesh& mesh, const TetHessian& hessian);

/// The `count` lowest modes of K φ = ω² M φ with M = diag(mass ⊗ I_d), d = 3
/// (K is 3N by 3N, DoF 3i + c) or d = 1 (K is N by N, scalar fields). Nodes with
/// mass 0 are fixed (their rows of Φ are 0); K restricted to the others must be
/// positive definite. Fails (naming the reason) on wrong sizes, a negative or
/// non-finite mass, count outside [1, free DoFs − 1], a K that its Cholesky factorization
/// finds not positive definite or a Lanczos
/// run that does not converge.
VibrationModes lowest_vibration_modes(const Eigen::SparseMatrix<double>& K, const VecX& mass, int count);

/// #N lumped nodal masses (kg) of the Simulated nodes, ρ_t V_t / 4 per tet corner;
/// 0 at every other node (bone, skinned: their displacement is held at 0).
VecX simulated_lumped_mass(const Avatar& avatar);

/// The avatar's soft-tissue modes: K of its materials in their frames at rest
/// (linearized_hessian), the lumped mass of the Simulated nodes (density × V / 4
/// per tet), every node that is not Simulated fixed.
VibrationModes soft_tissue_modes(const Avatar& avatar, int count);

/// Scalar skinning eigenmodes (in the spirit of Benchekroun et al. 2023, the third
/// candidate basis): the lowest eigenvectors of L w = λ M w, L = Σ_t V_t μ_t G_tᵀ G_t the
/// shear-modulus-weighted stiffness Laplacian (μ_t from the mean of the tet's three Young's
/// moduli and its Poisson ratio), M the lumped mass of the Simulated nodes, every other node
/// held at 0. phi is #N by count: weights for u = W z, 3 DoFs each, like the handles' W.
VibrationModes skinning_eigenmodes(const Avatar& avatar, int count);

}  // namespace sflsh
