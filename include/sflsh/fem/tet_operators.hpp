#pragma once
// Linear (P1) finite-element operators on a tetrahedral mesh: element volumes,
// shape-function gradients, the stiffness ("cotangent") Laplacian and the mass
// matrices. libigl's cotmatrix/massmatrix, with the sign convention of FEM
// stiffness: L is positive semi-definite.
#include <utility>
#include <vector>

#include <Eigen/Sparse>

#include "sflsh/core/types.hpp"
#include "sflsh/mesh/tet_mesh.hpp"

namespace sflsh::fem {

/// Shape-function gradients of one tet: row a is ∇φ_a (1/m), a = 0..3.
using TetGradient = Eigen::Matrix<double, 4, 3>;

/// #T signed volumes (m^3) of the tets; positive for positively oriented tets.
VecX tet_volumes(const TetMesh& mesh);

/// #T gradients ∇φ_a of the four linear shape functions of each tet (1/m).
/// Fails (naming the tet) if a tet is degenerate or inverted, because every
/// operator below would be meaningless there.
std::vector<TetGradient> tet_gradients(const TetMesh& mesh);

/// Gradients of a reduced basis in tet t: d_{t,k} = Σ_n W_{n,k} ∇φ_n (1/m) for
/// the columns k of W (#N by #K) that are non-zero at a node of t, sorted by
/// k. Nodes whose `node_role` is not Simulated (0) carry no W (empty role: all
/// do). `grad` is tet t's entry of tet_gradients.
std::vector<std::pair<int, Vec3>> handle_gradients(const TetMesh& mesh, const TetGradient& grad,
                                                   const Eigen::SparseMatrix<double, Eigen::RowMajor>& W,
                                                   const VecXi& node_role, int t);

/// #N by #N stiffness Laplacian L = Σ_e w_e V_e G_eᵀ G_e (m times the unit of w),
/// with G_e the 3 by 4 gradient matrix of tet e and w_e = `tet_weight`[e] (#T,
/// e.g. a shear modulus; empty: 1). Symmetric PSD for w ≥ 0; rows sum to zero;
/// with constant w, L·f = 0 at interior nodes for every linear f. (Minus the
/// "cotangent Laplacian".) Fails if `tet_weight` is not empty and not #T long.
Eigen::SparseMatrix<double> stiffness_laplacian(const TetMesh& mesh, const VecX& tet_weight = VecX());

/// #N lumped (barycentric) nodal masses (m^3 for unit density): each tet gives
/// V_e/4 to each of its nodes. Sums to the mesh volume.
VecX lumped_mass(const TetMesh& mesh);

/// #N by #N consistent P1 mass matrix (m^3, unit density):
/// M_ab = V_e (1 + δ_ab) / 20 per tet. Sums to the mesh volume.
Eigen::SparseMatrix<double> consistent_mass(const TetMesh& mesh);

/// Exact integral over the mesh of the piecewise-linear field with nodal values
/// `f` (#N by C): 1 by C, units of f times m^3. Σ_e V_e · mean of f at e's nodes.
Eigen::RowVectorXd integrate_linear(const TetMesh& mesh, const MatX& f);

}  // namespace sflsh::fem
