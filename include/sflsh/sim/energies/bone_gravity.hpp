#pragma once
// Gravity on the skeleton's own mass (seed §3: "a gravity term per bone"):
//   V = −Σ_i m_i g · c_i(q),   c_i = G_i c̄_i  (bone centre of mass, world).
// Bodies as in bone_inertia.hpp (the soft-tissue mass has its own gravity term).
// The potential is linear in world positions, so its Hessian is taken as zero
// (the exact tangent-space Hessian only holds the exponential map's curvature
// and is indefinite); this keeps the total Hessian PSD.
#include <vector>

#include "sflsh/sim/energies/bone_inertia.hpp"

namespace sflsh {

class BoneGravity : public EnergyTerm {
 public:
  explicit BoneGravity(std::vector<BoneBody> bodies);
  std::string name() const override { return "bone_gravity"; }
  /// V (J) with ctx.gravity (m/s²); gradient ∂V/∂ξ_i = (m_i g × c_i, −m_i g).
  BodyBlocks blocks() const override { return BodyBlocks::Bones; }
  double compute(const StepContext& ctx, const Configuration& q, VecRef* grad, MatRef* hess) const override;

 private:
  std::vector<BoneBody> bodies_;
};

}  // namespace sflsh
