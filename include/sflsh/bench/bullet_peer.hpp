#pragma once
// The peer: Bullet 3's deformable FEM (btDeformableMultiBodyDynamicsWorld,
// btDeformableNeoHookeanForce, implicit backward Euler with Bullet's Newton–Krylov
// solve) run on the avatar's own tet mesh, in the same process as `sflsh bench`.
//
// What is shared with the full-FEM reference (reference/full_fem.hpp):
//   - the tet mesh (#N nodes, #T tets, one Bullet tetra per tet) and the lumped
//     nodal masses m_n = Σ_{t∋n} ρ_t V_t / 4 (Bullet's nodal masses are set to them);
//   - the prescribed nodes: every node whose role is not Simulated (Bone and
//     Skinned) gets inverse mass 0 and, each step, the velocity that carries it
//     from where it is to its skinned rest position x_n = Σ_j w_nj G_j x̄_n at the
//     step's bones, so x_{n+1} = x_n + h v lands on it (to round-off);
//   - the time step h, gravity, and no damping (Bullet's Neo-Hookean damping = 0).
//
// What differs, by construction of the peer:
//   - Material. Ours is orthotropic StVK with Fung saturation per region; Bullet's
//     is the stable Neo-Hookean of Smith et al. 2018, isotropic, one (μ_B, λ_B)
//     per force. At small strain we match the isotropic Voigt average of our
//     stiffness (isotropic_equivalent) and convert it with neo_hookean_lame, so
//     that Bullet's stress at F = I + δF is μ(δF + δFᵀ) + λ tr(δF) I to first
//     order. Per-region moduli enter through each tetra's element measure
//     (Bullet's force on a tet is m_element_measure · P(F; μ_B, λ_B), linear in
//     (μ_B, λ_B) at a fixed ratio): tet t's measure is V_t · μ_t / μ_B. This is
//     exact when every region has the same λ/μ (the default avatar: the same
//     orthotropy 1.5 : 1 : 0.5 and ν everywhere); otherwise λ uses the
//     volume-weighted mean ratio and lambda_mismatch() reports the worst error.
//   - Rest shape. Bullet's elastic energy is measured from the unposed tet mesh
//     to the world positions, so skinning distortion (LBS at joints) strains
//     Bullet's tets; ours measures strain on the soft displacement u alone.
//     With BulletPeerOptions::rest_follows_skinning each tetra's rest shape is
//     re-posed every step to the skinned rest positions (Dm⁻¹ and the measure),
//     which removes that difference for a near-rigid skinning transform.
//
// Soft displacement (as for the reduced rows, in the unposed space):
//   u_n = A_n⁻¹ (x_n − Σ_j w_nj G_j x̄_n),   A_n = Σ_j w_nj R_j,
// exact because linear blend skinning is affine in the unposed point.
#include <memory>
#include <vector>

#include "sflsh/asset/avatar.hpp"
#include "sflsh/core/types.hpp"
#include "sflsh/sim/configuration.hpp"

namespace sflsh {

/// Lamé parameters (Pa).
struct LameParameters {
  double mu = 0, lambda = 0;
};

/// The isotropic small-strain equivalent of a region's orthotropic StVK
/// material (sim/material.hpp): the Voigt average of its stiffness over all
/// orientations, i.e. the bulk modulus K = (ΣC_ii + 2Σ_{i<j}C_ij)/9 and shear
/// modulus G = (ΣC_ii − Σ_{i<j}C_ij + 3ΣG_ij)/15 of C_ij = √(E_iE_j)(δ_ij + ν/(1−2ν))/(1+ν),
/// G_ij = √(E_iE_j)/(2(1+ν)); μ = G, λ = K − 2G/3. Equal Young's moduli E give
/// μ = E/(2(1+ν)), λ = Eν/((1+ν)(1−2ν)). Fung saturation and the compression
/// barrier have no second-order term at F = I and do not enter.
LameParameters isotropic_equivalent(const RegionMaterial& material);

/// Bullet's stable Neo-Hookean Ψ = μ_B/2 (I_C − 3) + λ_B/2 (J − 1 − ¾μ_B/λ_B)² − μ_B/2 log(I_C + 1)
/// linearizes at F = I to isotropic elasticity with μ = ¾μ_B, λ = λ_B − ⅝μ_B.
/// Returns the (μ_B, λ_B) that give `small_strain`: μ_B = 4/3 μ, λ_B = λ + 5/6 μ.
LameParameters neo_hookean_lame(const LameParameters& small_strain);

struct BulletPeerOptions {
  double h = 1.0 / 60.0;               ///< time step (s)
  Vec3 gravity = Vec3(0, -9.81, 0);    ///< m/s², world
  /// Re-pose each tetra's rest shape to the skinned rest positions every step
  /// (see above); false: Bullet's rest shape is the unposed mesh.
  bool rest_follows_skinning = false;
  /// Newton iterations of Bullet's implicit solve at most (0: Bullet's default).
  int newton_iterations = 0;
  /// Bullet's backtracking line search on its step energy (setLineSearch).
  bool line_search = false;
};

/// One avatar's tet mesh as a Bullet deformable body (see the file comment).
class BulletPeer {
 public:
  /// Builds the Bullet world and soft body; nodes at the unposed rest positions,
  /// identity bones. Throws on an avatar without tets or with a degenerate tet.
  explicit BulletPeer(std::shared_ptr<const Avatar> avatar, BulletPeerOptions options = {});
  ~BulletPeer();
  BulletPeer(const BulletPeer&) = delete;
  BulletPeer& operator=(const BulletPeer&) = delete;

  /// Every node at its skinned rest position for `bones` (24 world transforms), zero velocity.
  void reset(const std::vector<Isometry>& bones);
  /// One Bullet step of h to the bones `bones_next` (prescribed nodes moved
  /// kinematically onto their skinned rest positions). Returns the wall time
  /// (ms) of the step, setting the prescribed nodes included.
  double step(const std::vector<Isometry>& bones_next);

  /// Nodes and tetras of the Bullet soft body.
  int num_nodes() const;
  int num_tets() const;
  /// Nodes with inverse mass 0 (every non-Simulated node).
  int num_prescribed() const;
  /// Bullet's nodal masses (kg, #N; 0 at prescribed nodes).
  VecX node_masses() const;
  /// #N by 3 Bullet node positions (m, world).
  Points positions() const;
  /// #N by 3 skinned rest positions Σ_j w_nj G_j x̄_n at `bones` (m, world).
  Points skinned_rest(const std::vector<Isometry>& bones) const;
  /// #N by 3 soft displacement u_n (m, unposed) at the current bones; rows of
  /// prescribed nodes are 0.
  Points soft_displacement() const;
  /// Smallest det F over Bullet's tetras at the current positions (volume
  /// ratio to the rest shape; ≤ 0: an inverted tetra).
  double min_volume_ratio() const;
  /// (μ_B, λ_B) held by Bullet's Neo-Hookean force (Pa).
  LameParameters bullet_lame() const;
  /// Small-strain (μ, λ) Bullet applies in tet t: ¾μ_B s_t, (λ_B − ⅝μ_B) s_t with
  /// s_t = element measure / volume.
  LameParameters tet_small_strain_lame(int t) const;
  /// Largest relative error of λ over the tets (0 when every region has the same λ/μ).
  double lambda_mismatch() const { return lambda_mismatch_; }
  /// Bullet's implicit solver settings: Newton iterations at most, residual tolerance.
  int newton_iterations() const;

 private:
  struct World;
  void move_prescribed(const std::vector<Isometry>& bones);
  void pose_rest_shapes(const Points& skinned);

  std::shared_ptr<const Avatar> avatar_;
  BulletPeerOptions options_;
  std::unique_ptr<World> world_;
  std::vector<int> prescribed_;  // node indices with inverse mass 0
  VecX volume_;                  // #T rest volumes (m³, unposed, > 0)
  VecX scale_;                   // #T stiffness scale s_t
  double lambda_mismatch_ = 0;
  std::vector<Isometry> bones_;
};

}  // namespace sflsh
