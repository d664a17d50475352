#pragma once
// Gravity on the soft body: E(q) = −Σ_s m_s g·x_s(q) over the `inertia`
// cubature (m_s = ρ_s c_s). Linear in world positions, so the Hessian with
// respect to z is zero; the curvature through bone rotations is indefinite and
// left out (Gauss–Newton), so this term adds nothing to the Hessian.
#include "sflsh/sim/energy_term.hpp"
#include "sflsh/sim/posed_points.hpp"

namespace sflsh {

class GravityTerm : public EnergyTerm {
 public:
  /// Uses avatar.inertia; the gravity vector is ctx.gravity (m/s²).
  explicit GravityTerm(const Avatar& avatar);
  std::string name() const override { return "gravity"; }
  double compute(const StepContext& ctx, const Configuration& q, VecRef* grad, MatRef* hess) const override;

 private:
  PosedPoints points_;
  VecX mass_;
};

}  // namespace sflsh
