#pragma once
// Joint limits (seed §3): a smooth one-sided quadratic penalty on each
// component of the local rotation vector θ_j = log(R_pᵀ R_j) outside its
// anatomical range (joint_limits_table.hpp):
//   E = Σ_j ½ k_j Σ_a (θ_ja − clamp(θ_ja, lower_ja, upper_ja))²,
// zero inside the range, C¹ across its boundary. Derivative of the log map
// (parent frame): dθ/dω_j = J_l⁻¹(θ) R_pᵀ, dθ/dω_p = −J_l⁻¹(θ) R_pᵀ
// (bone_residual.hpp); Gauss–Newton Hessian.
#include <vector>

#include "sflsh/sim/energies/bone_residual.hpp"
#include "sflsh/sim/joint_limits_table.hpp"

namespace sflsh {

class JointLimit : public BoneLeastSquaresTerm {
 public:
  /// `ranges` and `stiffness` (N·m/rad, per joint) for each of the avatar's
  /// joints; joints with `limited == false` or zero stiffness are skipped.
  JointLimit(const Avatar& avatar, std::vector<JointRange> ranges, std::vector<double> stiffness);
  std::string name() const override { return "joint_limit"; }
  void residuals(const StepContext& ctx, const Configuration& q, std::vector<BoneResidual>& out) const override;

 private:
  std::vector<int> parents_;
  std::vector<JointRange> ranges_;
  std::vector<double> stiffness_;
};

}  // namespace sflsh
