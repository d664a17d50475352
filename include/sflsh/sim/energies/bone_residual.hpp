#pragma once
// Least-squares building blocks shared by the skeletal terms (seed §3):
// bone inertia, joint constraints, joint limits and tracking springs are all
//   E = Σ_b ½ r_bᵀ W_b r_b,
// with each residual r_b ∈ R^3 depending on at most two bones. One assembly
// (value, gradient Jᵀ W r, Gauss–Newton Hessian Jᵀ W J, which is PSD by
// construction) serves them all. Jacobians are with respect to the left,
// world-frame tangent steps ξ_i = (ω_i, v_i) of configuration.hpp.
#include <array>
#include <string>
#include <vector>

#include "sflsh/sim/energy_term.hpp"

namespace sflsh {

using Mat36 = Eigen::Matrix<double, 3, 6>;

/// One residual block: r (3), its SPD weight W (3x3; energy ½ rᵀ W r) and the
/// Jacobians dr/dξ of up to two bones (bone index −1 = unused slot).
struct BoneResidual {
  Vec3 r = Vec3::Zero();
  Mat3 W = Mat3::Zero();
  std::array<int, 2> bones{{-1, -1}};
  std::array<Mat36, 2> J{{Mat36::Zero(), Mat36::Zero()}};
};

/// Inverse of SO(3)'s left Jacobian: log(exp(δ) exp(φ)) = φ + J_l⁻¹(φ) δ + O(δ²)
/// (Chirikjian 2011, eq. 10.86). Finite for |φ| ≤ π; Taylor branch near 0.
Mat3 so3_left_jacobian_inverse(const Vec3& phi);

/// Jacobian block of a world point x = G_i p̄ carried by bone i:
/// dx/dξ_i = [−[x]×, I] (configuration.hpp).
Mat36 point_jacobian(const Vec3& x_world);

/// Rotation residual r = log(R_a C R_bᵀ) (world frame, rad): zero when
/// R_a = R_b Cᵀ. b = −1 means R_b = I, i.e. bone a against the fixed rotation
/// Cᵀ. Weight W (3x3). Jacobians: dr/dω_a = J_l⁻¹(r), dr/dω_b = −J_l⁻¹(r)ᵀ
/// (the inverse right Jacobian); translations do not enter.
BoneResidual rotation_residual(const Configuration& q, int a, const Mat3& C, int b, const Mat3& W);

/// Adds ½ rᵀ W r for every block and returns the sum (J). If the layout
/// solves for bones, also adds Jᵀ W r to `grad` and the Gauss–Newton Jᵀ W J
/// to `hess` (either may be null); with kinematic bones it adds nothing.
double accumulate_residuals(const std::vector<BoneResidual>& blocks, const DofLayout& layout, VecRef* grad,
                            MatRef* hess);

/// Base of the least-squares skeletal terms: subclasses only list residuals.
class BoneLeastSquaresTerm : public EnergyTerm {
 public:
  /// Residual blocks at q (appended to `out`). Public so tests can check the
  /// Jacobians against finite differences of r itself.
  virtual void residuals(const StepContext& ctx, const Configuration& q, std::vector<BoneResidual>& out) const = 0;
  BodyBlocks blocks() const override { return BodyBlocks::Bones; }
  double compute(const StepContext& ctx, const Configuration& q, VecRef* grad, MatRef* hess) const override;
};

}  // namespace sflsh
