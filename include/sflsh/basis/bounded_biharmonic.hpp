#pragma once
// Bounded biharmonic weights (Jacobson et al. 2011, "Bounded Biharmonic Weights
// for Real-Time Deformation"; as the reduced basis of Wang et al. 2015 and
// Tapia et al. 2021, seed §4).
//
// For each handle k:   minimize ½ wᵀ Q w,   Q = L M⁻¹ L
//   subject to w = 1 at handle k's node, w = 0 at the other handles' nodes and
//   at every Dirichlet node (Bone, Skinned), and 0 ≤ w ≤ 1 elsewhere,
// with L the P1 stiffness Laplacian and M the lumped mass (tet_operators.hpp).
// Because L carries its (Neumann) boundary rows, the discrete energy also
// drives ∂w/∂n → 0 on the mesh boundary as h → 0 (Jacobson et al. 2010; Stein
// et al. 2018): in 1-D with w(0)=1, w(1)=0 the limit is the cubic 1 − 3s² + 2s³.
//
// QP method — primal–dual active set (Hintermüller, Ito & Kunisch 2002, a
// semismooth Newton method), one independent QP per handle:
//  1. Start: free nodes within r = initial_radius_factor · (V/K)^(1/3) of the
//     handle are inactive, all others at the lower bound 0. (The bounded
//     weights have compact support a few handle spacings wide, whereas the
//     unconstrained biharmonic functions oscillate over the whole mesh: a
//     local start beats starting from them.)
//  2. Iterate: fix the active nodes at their bound, solve
//     Q_II w_I = −q_I − Q_IA w_A on the inactive set I with a CHOLMOD
//     factorization of that block, compute the multipliers g = Q_ff w + q,
//     move inactive nodes that left [0,1] to the active set and release active
//     nodes whose multiplier has the wrong sign (this also grows the support).
//     When the set stops changing, w satisfies the KKT conditions exactly (a
//     finite, combinatorial test). After `pdas_iterations` the update only
//     adds (or, when nothing is violated, only releases), which removes the
//     cycling PDAS can show on non-M-matrices like Q; a node bound again
//     after `max_releases` such releases stays bound, so the iteration ends even
//     where add and release alternate (long thin supports: free bones). It
//     also ends once the KKT residual is below `kkt_tolerance`.
//  Handles are solved in parallel (one thread per core). Cost: the active set
//  moves a couple of node rings per iteration while growing, and then creeps
//  (changes shrink by about half per iteration) as the C¹ support boundary of
//  the biharmonic obstacle problem settles, so ~15–25 iterations are typical.
//  Late iterations change few nodes, so the linear systems are solved against
//  the factorization of an earlier inactive block, bordered by the changed
//  nodes (Schur complement / capacitance matrix, with cached F⁻¹B columns);
//  the block is refactored only when the border would exceed
//  `max_border_columns`. That halves the number of factorizations; the
//  bordered solve is exact (not an approximation), so the iterates and the
//  KKT test are those of plain PDAS up to round-off.
// Convergence is shown by the KKT residual (below) after every iteration.
#include <string>
#include <vector>

#include <Eigen/Sparse>

#include "sflsh/core/types.hpp"
#include "sflsh/mesh/tet_mesh.hpp"

namespace sflsh::basis {

/// How the basis meets the bone (bounded_biharmonic_weights).
enum class BoneCondition {
  /// Jacobson et al. 2011 as the seed states it: Bone nodes are Dirichlet 0 in
  /// every QP. On a thin shell of flesh (the default body: 98 % of the
  /// Simulated nodes are on the skin, 78 % of those share a tet edge with a
  /// bone node) the weights fall from 1 at a handle to 0 within a few shell
  /// thicknesses, so most of the skin keeps Σ_k W_k ≈ 0 (27 % of the
  /// skin nodes reach 0.5 at K = 64).
  Dirichlet,
  /// The QPs hold only the handles and the Skinned nodes fixed (bone nodes are
  /// free, Neumann), so each handle's weight spreads along the flesh up to the
  /// neighbouring handles; every Simulated row is then normalized to a
  /// partition of unity and blended to 0 at the bone by the harmonic depth
  /// fraction b (depth_fraction.hpp, 0 at Bone/Skinned nodes, 1 on the skin):
  ///   W_ik = b_i · w̃_ik / max(Σ_k w̃_ik, normalization_floor).
  /// Bone and Skinned rows are 0, so u = 0 there as before; Σ_k W_ik = b_i on
  /// rows the handles reach, so the skin is fully covered.
  DepthBlend,
};

struct BbwOptions {
  /// Default: DepthBlend (see BoneCondition).
  BoneCondition bone_condition = BoneCondition::DepthBlend;
  /// DepthBlend only: rows with Σ_k w̃_k below this are divided by it rather
  /// than by their sum, so a node no handle reaches keeps Σ_k W_k < 1 and
  /// the weights ramp to 0 instead of jumping. Dimensionless.
  double normalization_floor = 1e-3;
  /// Active-set iterations per handle before giving up (an error).
  int max_iterations = 100;
  /// Plain PDAS iterations before switching to the add-only/release-only update.
  int pdas_iterations = 20;
  /// Releases of a node after `pdas_iterations` before it stays at its bound.
  int max_releases = 1;
  /// Relative multiplier tolerance: an active node is released when its
  /// multiplier has the wrong sign by more than this times ‖q‖∞.
  double multiplier_tolerance = 1e-9;
  /// A column also stops once its KKT residual (BbwReport::kkt_residual) is
  /// at most this, even if the active set still changes: with free bones
  /// (DepthBlend) a few columns otherwise toggle nodes whose multipliers are
  /// near zero for 100 iterations at residuals of 4e-9 to 7e-8. 1e-6 is two
  /// orders below drop_tolerance.
  double kkt_tolerance = 1e-6;
  /// Weights below this are dropped from the sparse W (the bone complement
  /// 1 − Σ_k w_k absorbs them, so the partition of unity is unaffected).
  /// Biharmonic weights decay smoothly but never reach 0 in the interior: at
  /// 1e-8 a simulated node keeps ~12 handles and an elastic sample sees ~35
  /// (of 64); at 1e-4, ~3 and ~13, which makes the per-step elastic Hessian
  /// ~7x cheaper while changing u by at most 1e-4 of a handle displacement.
  double drop_tolerance = 1e-4;
  /// Start radius of each column's local domain, times (volume / #columns)^(1/3).
  /// Final supports reach ~1.5–2.2 of this unit; starting near that skips most
  /// of the ring-by-ring growth, starting far beyond it makes the first
  /// solves oscillate.
  double initial_radius_factor = 2.0;
  /// Largest border (changed nodes, cached columns) solved against an old
  /// factorization before the inactive block is refactored; 0 refactors every
  /// iteration. A border column costs about 1/100 of a factorization.
  int max_border_columns = 200;
  /// Compact support (m; 0 = off, the default). When positive, column k is
  /// the bounded biharmonic function restricted to its support: the nodes
  /// whose shortest path along tet edges to the column's nonzero fixed nodes
  /// (handle k) is at most this long. Every node outside is held at 0 like a
  /// Dirichlet node. Because Q = L M⁻¹ L also carries the Laplacian rows of
  /// the held nodes next to the support, the minimizer meets 0 with zero slope
  /// there (C¹, no crease): in 1-D, a handle at c with radius r gets
  /// 1 − 3s² + 2s³, s = |x − c| / r. The weight is exactly 0 outside the support,
  /// so a cubature sample sees only the handles within this distance.
  /// Negative or NaN: an error.
  double support_radius = 0.0;
  /// Compact support sized by the handle spacing (bounded_biharmonic_weights
  /// only; 0 = off, the default): handle k's radius is this times the
  /// distance from its node to the nearest other handle's node, so sparse
  /// handles (limbs) get wide supports and dense ones (trunk) narrow ones,
  /// and the handles per cubature sample stay about even. Exclusive with
  /// support_radius. Negative or NaN: an error.
  double support_spacing_factor = 0.0;
  /// Show a progress line (sflsh::Progress) over handles.
  bool show_progress = true;
  /// Threads that solve the columns (each column on one thread; the result
  /// does not depend on it); 0 = one per core. `precompute --threads`; a batch
  /// gives each of its worker processes cores / workers.
  int threads = 0;
};

/// What the solve did (Ceres-style summary). Residuals are dimensionless.
struct BbwReport {
  int num_nodes = 0, num_free = 0, num_handles = 0;
  int max_iterations = 0;        ///< active-set iterations, max over handles
  double mean_iterations = 0.0;  ///< mean over handles
  double mean_factorizations = 0.0;  ///< CHOLMOD factorizations per handle (the dominant cost)
  int max_inactive = 0;          ///< largest inactive set solved (nodes)
  /// Convergence: entry i is the max over handles of the KKT residual after
  /// active-set iteration i+1 (a handle that stopped keeps its last value).
  std::vector<double> kkt_history;
  /// Final KKT residual, max over handles and nodes of: bound violation, and
  /// the projected gradient |g_i| (free), max(0,−g_i) (at 0), max(0,g_i) (at 1),
  /// divided by ‖q‖∞ of that handle.
  double kkt_residual = 0.0;
  // Filled by bounded_biharmonic_weights (the full basis):
  double max_bound_violation = 0.0;  ///< of the stored W, and of the bone complement
  double partition_error = 0.0;      ///< max_i |Σ_k W_ik + w_bone,i − 1|, w_bone clamped to [0,1]
  double max_sum_before_normalization = 0.0;  ///< max_i Σ_k w_ik of the QP solutions
  int nodes_normalized = 0;          ///< rows rescaled (Dirichlet: Σ_k w_k > 1; DepthBlend: every reached Simulated row)
  int nodes_unreached = 0;           ///< DepthBlend: Simulated rows with Σ_k w̃_k < normalization_floor
  long nonzeros = 0;                 ///< stored entries of W
  double support_radius = 0.0;       ///< largest support radius used (m; 0 = unrestricted)
  int max_support_nodes = 0;         ///< support_radius > 0: largest support (free nodes inside), over columns
  double seconds_setup = 0.0, seconds_active_set = 0.0;  ///< operators; all QPs
  /// Multi-line human-readable summary.
  std::string summary() const;
};

/// Low level (libigl bbw style): bounded biharmonic functions with general
/// Dirichlet data. `fixed`: #B distinct node indices; `fixed_values`: #B by #C
/// values there. Each of the #C columns is an independent QP over the free
/// nodes with 0 ≤ w ≤ 1. Returns #N by #C (fixed rows hold their values).
/// Fails if a connected component of the mesh has no fixed node (Q_ff would be
/// singular). Fills `report` (the full-basis fields stay 0) if given.
MatX bounded_biharmonic_qp(const TetMesh& mesh, const VecXi& fixed, const MatX& fixed_values,
                           const BbwOptions& options = {}, BbwReport* report = nullptr);

/// The reduced basis: #N by #K weights W of the #K control handles
/// (`handle_nodes`, distinct Simulated nodes), zero at every Dirichlet node
/// (`node_role` #N: NodeRole Bone or Skinned).
///
/// options.bone_condition = DepthBlend (default): see BoneCondition. Then
/// 0 ≤ W ≤ 1, Σ_k W_ik = b_i ≤ 1 (w_bone = 1 − b_i) and at handle k's node the
/// row is b · e_k (e_k for a handle on the skin).
///
/// Dirichlet: the bone handle's weight is the complement w_bone = 1 − Σ_k w_k. The K QPs
/// are independent, so nothing forces Σ_k w_k ≤ 1; each row with Σ_k w_k > 1
/// is divided by that sum. This keeps 0 ≤ w ≤ 1, keeps the handle
/// interpolation (at handle k's node the row is e_k, sum 1) and the Dirichlet
/// zeros, and makes w_bone ∈ [0,1], so {W_k, w_bone} is a partition of unity.
/// (The summed QPs are feasible for a joint problem with Σ ≤ 1 only after this
/// rescaling; Jacobson et al. 2011 normalize in the same spirit.)
/// Then entries below options.drop_tolerance are dropped. Units: none.
Eigen::SparseMatrix<double, Eigen::RowMajor> bounded_biharmonic_weights(const TetMesh& mesh, const VecXi& node_role,
                                                                        const VecXi& handle_nodes,
                                                                        const BbwOptions& options = {},
                                                                        BbwReport* report = nullptr);

/// #N bone weight w_bone = clamp(1 − Σ_k W_ik, 0, 1) of the basis W (#N by #K).
VecX bone_weight(const Eigen::SparseMatrix<double, Eigen::RowMajor>& W);

}  // namespace sflsh::basis
