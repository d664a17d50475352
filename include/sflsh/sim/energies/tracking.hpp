#pragma once
// Tracking constraints between the skeleton and the target configuration of
// the motion (seed §3: "implemented as joint rotation springs"), plus a spring
// on the root joint's position:
//   E = Σ_j ½ k_j |log(R_local,j R_target,jᵀ)|² + ½ k_pos |G_0 J̄_0 − (J̄_0 + t_target)|²,
// target = ctx.target_pose (local axis-angle per joint, root translation) at
// t + h. Joint 0's spring acts on the root's world orientation. The residual
// is evaluated in the world frame, log(R_j T_jᵀ R_pᵀ) = R_p log(R_pᵀ R_j T_jᵀ)
// (same norm, simpler Jacobians; bone_residual.hpp); Gauss–Newton Hessian.
//
// Stiffness: a spring k with the inertia I it drives has natural frequency
// √(k/I); add_skeleton_terms sets k_j = I_j (2π f)² from each joint's subtree
// inertia so every joint tracks with the same frequency f (a constant target
// acceleration a is then followed with a lag of a/(2π f)²).
//
// Force limit (scenes with contact): with position_force_limit F > 0 the
// horizontal part r_h of the root position residual (perpendicular to
// ctx.gravity; all of r without gravity) gets a Huber spring, ½ k|r_h|² for
// |r_h| ≤ d = F/k and F (|r_h| − d/2) beyond, so the motion pulls the body
// along its path with at most F newtons: a body walking into another is
// stopped by contact instead of being pushed through it by an unbounded
// spring. The vertical part keeps the plain spring (the motion still carries
// the body's weight). Hessian beyond d: the secant (F/|r_h|) on the horizontal (PSD).
#include <vector>

#include "sflsh/sim/energies/bone_residual.hpp"

namespace sflsh {

class Tracking : public BoneLeastSquaresTerm {
 public:
  /// Rotation spring stiffness per joint (`rotation_stiffness`, #J, N·m/rad;
  /// 0 = not tracked; entry 0 = root orientation) and the root position
  /// spring (`position_stiffness`, N/m; 0 = off).
  /// `position_force_limit` (N, 0 = none): see the header comment.
  Tracking(const Avatar& avatar, std::vector<double> rotation_stiffness, double position_stiffness,
           double position_force_limit = 0.0);
  std::string name() const override { return "tracking"; }
  /// The rotation springs, and the root position spring when it has no force limit.
  void residuals(const StepContext& ctx, const Configuration& q, std::vector<BoneResidual>& out) const override;
  double compute(const StepContext& ctx, const Configuration& q, VecRef* grad, MatRef* hess) const override;

 private:
  Points joints_rest_;
  std::vector<int> parents_;
  std::vector<double> k_rot_;
  double k_pos_;
  double force_limit_;
};

}  // namespace sflsh
