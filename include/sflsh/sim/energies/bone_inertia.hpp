#pragma once
// Rigid-body inertia of the skeleton's bones (seed §3: "the skeleton
// contributes to the mass matrix M rigid-body inertia terms associated with
// each bone"), in backward-Euler optimization form (seed eq. 1):
//   E = Σ_i 1/(2h²) [ m_i |c_i(q) − c*_i|² + Δω_iᵀ I_i Δω_i ],  Δω_i = log(R_i R*_iᵀ),
// with the explicit (constant-velocity) prediction
//   c*_i = 2 c_i(t) − c_i(t−h),   R*_i = exp(log(R_t R_{t−h}ᵀ)) R_t = R_t R_{t−h}ᵀ R_t,
// and I_i = R*_i I_i,rest R*_iᵀ the world inertia tensor about the centre of
// mass (frozen at the prediction so the metric is constant within a step).
//
// Mass budget: the body's mass is carried by the soft-tissue volume (the
// inertia cubature covers the whole tet volume, bones included), so these
// rigid bodies stand for the skeleton's *own* mass only — by default 15 % of
// the body mass (adult skeleton, bone + marrow), distributed over SMPL's bones
// with Winter's segment mass fractions (Winter 2009, Biomechanics and Motor
// Control of Human Movement, table 4.1). They keep the 6 DoFs of every bone
// (including twist about its own axis) well conditioned.
#include <vector>

#include "sflsh/sim/energies/bone_residual.hpp"

namespace sflsh {

/// Rigid body standing for one bone (unposed frame).
struct BoneBody {
  double mass = 0.0;             ///< kg
  Vec3 com_rest = Vec3::Zero();  ///< centre of mass, m, unposed
  Mat3 inertia_rest = Mat3::Zero();  ///< kg m², about com_rest, unposed axes
};

/// Winter's segment mass fractions mapped to SMPL's 24 bones (bone j = the
/// segment from joint j to its children); they sum to 1. The trunk (0.497) is
/// split pelvis/abdomen/thorax, the thorax shared with the collars; head+neck,
/// hand and foot fractions are split between the two SMPL bones they span.
const std::vector<double>& smpl_segment_mass_fractions();

/// Rigid bodies of the 24 bones for a total mass `total_mass` (kg) split by
/// smpl_segment_mass_fractions(). Geometry: bone j is a set of thin solid rods
/// from joint j to each child joint (mass shared equally), or for a leaf
/// (head, hands, toes) one rod continuing the parent bone's direction for half
/// its length; rod radius 0.05·L + 1 cm. The centre of mass and the inertia
/// tensor (parallel-axis sum of the rods) follow. Requires 24 joints.
std::vector<BoneBody> bone_bodies(const Avatar& avatar, double total_mass);

/// Total mass (kg) of `bodies`.
double total_mass(const std::vector<BoneBody>& bodies);

class BoneInertia : public BoneLeastSquaresTerm {
 public:
  /// One rigid body per bone (#bones of the configuration).
  explicit BoneInertia(std::vector<BoneBody> bodies);
  std::string name() const override { return "bone_inertia"; }
  /// Computes the predictions c*_i, R*_i from ctx.q_prev and ctx.q_prev2 (an
  /// empty q_prev2 means "at rest").
  /// The predictions live in the term's cache (make_cache).
  std::unique_ptr<TermCache> make_cache() const override;
  void begin_step(const StepContext& ctx) const override;
  void residuals(const StepContext& ctx, const Configuration& q, std::vector<BoneResidual>& out) const override;

  const std::vector<BoneBody>& bodies() const { return bodies_; }

 private:
  std::vector<BoneBody> bodies_;
};

}  // namespace sflsh
