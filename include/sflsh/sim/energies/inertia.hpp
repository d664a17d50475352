#pragma once
// Soft-body inertia of backward Euler (Gast et al. 2015; seed §1, §4): the
// kinetic term 1/(2h²)‖x(q) − x*‖²_M integrated over the volume with the
// avatar's `inertia` cubature, in WORLD space so that it couples bones and z:
//   E(q) = Σ_s m_s / (2h²) |x_s(q) − x*_s|²,   m_s = ρ_s c_s (kg),
//   x*_s = 2 x_s(q_prev) − x_s(q_prev2)   (explicit prediction, computed in begin_step;
// backward Euler with velocity (x_t − x_{t−1})/h).
// Gradient exact; Hessian Gauss–Newton (1/h²) Jᵀ M J (PSD), J = ∂x/∂δ.
#include "sflsh/sim/energy_term.hpp"
#include "sflsh/sim/posed_points.hpp"

namespace sflsh {

class InertiaTerm : public EnergyTerm {
 public:
  /// Uses avatar.inertia; sample density from the region of its tet.
  explicit InertiaTerm(const Avatar& avatar);
  std::string name() const override { return "inertia"; }
  std::unique_ptr<TermCache> make_cache() const override;
  void begin_step(const StepContext& ctx) const override;
  double compute(const StepContext& ctx, const Configuration& q, VecRef* grad, MatRef* hess) const override;

  /// #S sample masses (kg).
  const VecX& masses() const { return mass_; }
  const PosedPoints& points() const { return points_; }

 private:
  PosedPoints points_;
  VecX mass_;
};

/// #S masses ρ(region of the sample's tet) · weight (kg) of a cubature.
VecX cubature_masses(const Avatar& avatar, const Cubature& cubature);

}  // namespace sflsh
