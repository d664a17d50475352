#pragma once
// One potential/inertial term of the backward-Euler objective (Gast et al. 2015):
//   q_{t+1} = argmin  E(q) = Σ_terms E_term(q)
// Terms share this interface so the integrator does not know which exist; a
// scene adds only the terms it needs (STYLE.md). Each gives value, gradient and
// a positive semi-definite Hessian (projected, or Gauss–Newton) with respect to
// the tangent step at q (configuration.hpp), in the layout's ordering.
#include <memory>
#include <string>
#include <vector>

#include "sflsh/asset/avatar.hpp"
#include "sflsh/body/body_model.hpp"
#include "sflsh/sim/configuration.hpp"

namespace sflsh {

/// What a term may read about the step being taken.
struct StepContext {
  const Avatar* avatar = nullptr;
  DofLayout layout;
  double h = 1.0 / 60.0;            ///< time step, s
  Vec3 gravity = Vec3(0, -9.81, 0); ///< m/s^2, world
  Configuration q_prev;             ///< q at time t
  Configuration q_prev2;            ///< q at time t − h (velocity = (q_prev − q_prev2)/h)
  /// Target pose at t + h (motion tracking / prescribed bones); joint
  /// transforms of the target in `target_bones` (24 world transforms).
  BodyPose target_pose;
  std::vector<Isometry> target_bones;
};

class EnergyTerm {
 public:
  virtual ~EnergyTerm() = default;
  /// Short name for diagnostics ("inertia", "elastic", ...).
  virtual std::string name() const = 0;
  /// Called once per time step before the Newton iterations (e.g. to compute
  /// the explicit prediction x* from q_prev, q_prev2).
  virtual void begin_step(const StepContext& ctx) {}
  /// Energy at q (J). If `grad` is non-null, adds ∂E/∂δ (layout.size()); if
  /// `hess` is non-null, adds a PSD approximation of ∂²E/∂δ² (dense,
  /// layout.size() square). Returns +infinity for inadmissible q (e.g. an
  /// inverted element), which the line search rejects.
  virtual double evaluate(const StepContext& ctx, const Configuration& q, VecX* grad, MatX* hess) const = 0;
};

using EnergyTermPtr = std::unique_ptr<EnergyTerm>;

}  // namespace sflsh
