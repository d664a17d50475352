#pragma once
// The error floor of a reduced basis: the best approximation of a
// nodal soft displacement within span(U), U = W ⊗ I₃ (u_i = Σ_k W_ik z_k),
// in the mass-weighted least-squares sense, per frame:
//   z* = argmin_z Σ_i m_i ‖u_i − Σ_k W_ik z_k‖²  ⇔  (Wᵀ M W) z* = Wᵀ M u
// (the same K by K system for x, y and z). The gap between a simulation's
// error and the floor's is dynamics or integration error; the floor is basis
// error. Also: rel_err split by body region, so a good average cannot hide a
// rigid limb.
#include <vector>

#include <Eigen/Sparse>

#include "sflsh/core/types.hpp"

namespace sflsh {

/// Projection of nodal displacements onto span(W ⊗ I₃) with the mass metric.
class SubspaceProjector {
 public:
  /// `W` #N by #K basis weights, `mass` #N non-negative nodal masses (kg; 0
  /// excludes a node, e.g. a Dirichlet node). Fails if a column of W has no
  /// weight on a node with mass or Wᵀ M W is singular.
  SubspaceProjector(const Eigen::SparseMatrix<double, Eigen::RowMajor>& W, const VecX& mass);
  /// #K by 3 reduced coordinates z* of the nodal displacement `u` (#N by 3, m).
  MatX coordinates(const Points& u) const;
  /// #N by 3 best approximation W z* of `u` (m).
  Points project(const Points& u) const;

 private:
  Eigen::SparseMatrix<double, Eigen::RowMajor> W_;
  VecX mass_;
  Eigen::LDLT<MatX> gram_;  // Wᵀ M W
};

/// Projection onto the span of a general vector basis with the same mass metric:
///   c* = argmin_c Σ_i m_i ‖u_i − (B c)_i‖²,  B 3N by D, row 3i + c = component c at node i.
/// For bases that are not W ⊗ I₃, e.g. the handles' columns together with vibration modes
/// (soft_tissue_modes.hpp). Columns may be linearly dependent: the normal equations are
/// solved in the eigenbasis of Bᵀ M B, leaving out directions whose eigenvalue is below
/// 1e-12 of the largest (the minimum-norm solution; the projection is unique either way).
class VectorSubspaceProjector {
 public:
  /// `B` 3N by D, `mass` #N non-negative nodal masses (kg). Fails on wrong sizes, a
  /// negative or non-finite mass or a basis with no weight on any node with mass.
  VectorSubspaceProjector(MatX B, const VecX& mass);
  /// #N by 3 best approximation B c* of `u` (#N by 3, m).
  Points project(const Points& u) const;
  /// The dimension of span(B) on the nodes with mass (D less the directions left out).
  int rank() const { return int(kept_.cols()); }

 private:
  MatX B_;
  VecX mass3_;  // 3N: mass per DoF
  MatX kept_;   // D by r: eigenvectors of Bᵀ M B scaled by 1/sqrt(eigenvalue)
};

/// W ⊗ I₃ (#N by #K weights) as a dense 3N by 3K vector basis: column 3k + c
/// is W_·k along axis c.
MatX vector_basis(const Eigen::SparseMatrix<double, Eigen::RowMajor>& W);

/// Weights of the affine-handle basis of the same handles (a candidate basis, Wang et al.
/// 2015): u_i = Σ_k W_ik (t_k + A_k (x_i − c_k)), 12 DoFs per handle, as scalar weights for
/// SubspaceProjector: #N by 4K, column k = W_·k (translation), column K + 3k + c =
/// W_·k ∘ (x_c − c_{k,c}) (the c-th column of A_k). Where Σ_k W_ik = 1 every affine field
/// x ↦ A x + b lies in its span (t_k = A c_k + b, A_k = A). `nodes` #N by 3, `handles` #K by 3.
Eigen::SparseMatrix<double, Eigen::RowMajor> affine_handle_weights(const Eigen::SparseMatrix<double, Eigen::RowMajor>& W,
                                                                   const Points& nodes, const Points& handles);

/// Relative error per region: for each r in [0, num_regions),
///   sqrt(Σ_f Σ_{v: region[v] = r} ‖u_f(v) − ref_f(v)‖² / Σ_f Σ_{v: region[v] = r} ‖ref_f(v)‖²)
/// over frames f (the shorter of the two sequences) and points v with
/// `region[v]` = r (−1: in no region). A region with no points or zero
/// reference gives NaN. `u`, `ref`: per frame #V by 3; `region` #V labels.
std::vector<double> region_rel_errors(const std::vector<Points>& u, const std::vector<Points>& ref,
                                      const VecXi& region, int num_regions);

}  // namespace sflsh
