#pragma once
// Joint constraints keeping the skeleton connected (seed §3). Every bone is a
// free rigid body in q, so for each non-root joint j with parent p the joint's
// world position according to its own bone must equal that according to the
// parent's bone:
//   E = Σ_j ½ k |G_j J̄_j − G_p J̄_j|²     (Gauss–Newton Hessian).
//
// Why a penalty and not reduced (joint-angle) coordinates: q is fixed as
// per-bone transforms (DESIGN.md §4), which keeps every other term local to
// one or two bones and the Hessian's bone blocks simple; a quadratic penalty
// is one more term of the same optimization, needs no constraint solver, and
// its Gauss–Newton Hessian is PSD.
//
// Stiffness scales with the time step: k = ratio · M / h² (N/m), M a
// reference mass (the body's). A force M·a pulls a joint apart by
// a h² / ratio (body weight at h = 1/60 s, ratio 100: 0.03 mm), independent of
// M and vanishing with h; against the inertia M/h² the penalty is only
// `ratio` times stiffer, so the Newton system stays well conditioned
// (condition ~ ratio · M / m_smallest bone) whatever h is.
#include <vector>

#include "sflsh/sim/energies/bone_residual.hpp"

namespace sflsh {

class JointConstraint : public BoneLeastSquaresTerm {
 public:
  /// Skeleton from `avatar` (joints_rest, parents); k = stiffness_ratio ·
  /// reference_mass / h² (dimensionless ratio, kg).
  JointConstraint(const Avatar& avatar, double stiffness_ratio, double reference_mass);
  std::string name() const override { return "joint_constraint"; }
  void residuals(const StepContext& ctx, const Configuration& q, std::vector<BoneResidual>& out) const override;
  /// Penalty stiffness (N/m) at time step h (s).
  double stiffness(double h) const { return ratio_ * mass_ / (h * h); }

 private:
  Points joints_rest_;
  std::vector<int> parents_;
  double ratio_, mass_;
};

}  // namespace sflsh
