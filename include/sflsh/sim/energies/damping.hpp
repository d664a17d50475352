#pragma once
// Stiffness-proportional (Rayleigh) damping of the soft tissue as a backward-
// Euler potential: the damping force −β K₀ ż with ż = (z − z_prev)/h is the
// negative gradient of
//   E(z) = β / (2h) (z − z_prev)ᵀ K₀ (z − z_prev),
// K₀ = the elastic Hessian at rest (z = 0; PSD, constant so the term is exactly
// quadratic). β (s) sets the damping ratio ζ = β ω / 2 of a mode of angular
// frequency ω. Depends on z only.
#include "sflsh/sim/energies/elastic.hpp"
#include "sflsh/sim/energy_term.hpp"

namespace sflsh {

class DampingTerm : public EnergyTerm {
 public:
  /// `beta` in seconds (≥ 0); K₀ from `elastic` at z = 0.
  DampingTerm(const Avatar& avatar, const ElasticTerm& elastic, double beta);
  std::string name() const override { return "damping"; }
  BodyBlocks blocks() const override { return BodyBlocks::Soft; }
  double compute(const StepContext& ctx, const Configuration& q, VecRef* grad, MatRef* hess) const override;

 private:
  double beta_;
  MatX K0_;  // 3K by 3K (N/m)
};

}  // namespace sflsh
