#pragma once
// Soft-tissue elasticity in the unposed space (seed §4; DESIGN.md §4):
//   E(z) = Σ_k c_k Ψ(F_k),   F_k = I + ∂u/∂x̄ = I + Σ_h z_h d_{k,h}ᵀ,
// with the avatar's `elastic` cubature (c_k in m³) and the material and frame
// of the sample's tet (sim/material.hpp). Tets are linear, so ∂u/∂x̄ is constant
// per tet: d_{k,h} = Σ_n W_{n,h} ∇N_n (3-vector, 1/m) is precomputed for the
// handles h touching the tet (Dirichlet nodes contribute nothing).
// Depends on z only. Hessian: Σ_k c_k G_kᵀ ΠPSD(∂²Ψ/∂F²) G_k (per-sample 9x9
// eigenvalue clamping), G_k = ∂vec(F_k)/∂z, assembled 3x3 block by block over
// the sample's handles (~27 m² flops for m handles, no dense 9 by 3m product),
// into a scratch of the upper 3x3 blocks (9 contiguous doubles each; started
// at K for exact_quadratic) that is added to both triangles of the Hessian at the end.
#include <utility>
#include <vector>

#include "sflsh/sim/energy_term.hpp"
#include "sflsh/sim/material.hpp"

namespace sflsh {

class ElasticTerm : public EnergyTerm {
 public:
  /// Uses avatar.elastic, tet_frames, tet_region, materials. `project_psd` =
  /// false keeps the exact (possibly indefinite) Hessian, for derivative
  /// checks. `exact_quadratic` splits Ψ = Ψ₂ + (Ψ − Ψ₂), Ψ₂ the energy
  /// linearized at F = I: Ψ₂ is integrated over every tet once, here, as
  /// ½ zᵀ K z, and the cubature samples only the higher-order remainder.
  /// Small strains are then integrated exactly, which removes the soft modes
  /// of an under-sampled energy (bench: rel_err 0.62 → see README); the
  /// remainder keeps the barrier and saturation at large strains.
  /// `mean_dilatation` (with exact_quadratic) averages the volume change of
  /// Ψ₂ over cells of tets (linearized_stiffness.hpp): the subspace no longer
  /// locks on the near-incompressible tissue (bench: rel_err 0.33 → 0.20 on jump;
  /// keeps kPerTetVolumeShare of each tet's own volume change, and the samples
  /// carry the compression guard (compression_guard.hpp); the default).
  explicit ElasticTerm(const Avatar& avatar, bool project_psd = true, bool exact_quadratic = true,
                       bool mean_dilatation = true);
  std::string name() const override { return "elastic"; }
  BodyBlocks blocks() const override { return BodyBlocks::Soft; }
  /// Scratch of the Hessian assembly (kept in the State: no allocation per step).
  std::unique_ptr<TermCache> make_cache() const override;
  double compute(const StepContext& ctx, const Configuration& q, VecRef* grad, MatRef* hess) const override;

  /// Deformation gradient of sample k for reduced DoFs z.
  Mat3 deformation_gradient(int k, const VecX& z) const;
  int num_samples() const { return int(weight_.size()); }
  /// Smallest det F over the samples (> 0 means no inverted cubature element).
  double min_det(const VecX& z) const;
  /// Whether Ψ₂'s volume change is averaged per cell (constructor).
  bool mean_dilatation() const { return mean_dilatation_; }

 private:
  VecX weight_;                        // #S c_k (m³)
  std::vector<MaterialPoint> material_;  // #S, of the sample's tet (region and frame)
  std::vector<Mat9> linear_hessian_;    // #S ∂²Ψ₂/∂F² of the sample's material
  MatX K_;                              // 3K x 3K exact linearized stiffness (exact_quadratic)
  std::vector<double> K_blocks_;        // K_'s upper 3x3 blocks (sample_hessian.hpp layout)
  // The upper 3x3 blocks (i <= j) that can be nonzero: K_'s nonzero blocks and
  // every pair of handles sharing a sample. Only these are reset and added to
  // the Hessian (the others stay 0: with compactly supported weights most are).
  std::vector<std::pair<int, int>> blocks_used_;
  std::vector<int> start_{0}, handle_;  // CSR over samples: handles touching the tet
  std::vector<Vec3> d_;                 // per entry: ∂u/∂x̄ per unit z_h (1/m)
  int num_reduced_ = 0;
  bool project_psd_ = true;
  bool exact_quadratic_ = true;
  bool mean_dilatation_ = false;
};

/// Frame of tet t from avatar.tet_frames (row-major 3x3), or the identity when
/// the asset has no frames.
Mat3 tet_frame(const Avatar& avatar, int t);
/// Material of tet t (avatar.materials[tet_region[t]], or the first one when
/// tet_region is empty). Throws when the avatar has no materials.
const RegionMaterial& tet_material(const Avatar& avatar, int t);

}  // namespace sflsh
