#include "sflsh/sim/energies/bone_residual.hpp"

#include <cmath>

#include "sflsh/core/error.hpp"
#include "sflsh/core/rotation.hpp"

namespace sflsh {

Mat3 so3_left_jacobian_inverse(const Vec3& phi) {
  // J_l⁻¹(φ) = I − ½[φ]× + c(θ)[φ]×²,  c = 1/θ² − (1 + cos θ)/(2 θ sin θ).
  // c loses all digits to cancellation for small θ: use its series there.
  const double t2 = phi.squaredNorm();
  double c;
  if (t2 < 1e-4) {
    c = 1.0 / 12.0 + t2 / 720.0 + t2 * t2 / 30240.0;
  } else {
    const double t = std::sqrt(t2);
    // (1 + cos θ)/sin θ = cot(θ/2): finite (→ 0) at θ = π.
    c = 1.0 / t2 - 0.5 / (t * std::tan(0.5 * t));
  }
  const Mat3 K = hat(phi);
  return Mat3::Identity() - 0.5 * K + c * K * K;
}

Mat36 point_jacobian(const Vec3& x_world) {
  Mat36 J;
  J.leftCols<3>() = -hat(x_world);
  J.rightCols<3>().setIdentity();
  return J;
}

BoneResidual rotation_residual(const Configuration& q, int a, const Mat3& C, int b, const Mat3& W) {
  BoneResidual res;
  const Mat3 Rb = b < 0 ? Mat3::Identity() : Mat3(q.bones[b].linear());
  res.r = rotation_log(q.bones[a].linear() * C * Rb.transpose());
  res.W = W;
  const Mat3 Jinv = so3_left_jacobian_inverse(res.r);
  // exp(ω_a) R_a C R_bᵀ = exp(ω_a) exp(r)  ->  r + J_l⁻¹(r) ω_a;
  // R_a C R_bᵀ exp(−ω_b) = exp(r) exp(−ω_b) -> r − J_r⁻¹(r) ω_b, J_r⁻¹(r) = J_l⁻¹(r)ᵀ.
  res.bones[0] = a;
  res.J[0].leftCols<3>() = Jinv;
  if (b >= 0) {
    res.bones[1] = b;
    res.J[1].leftCols<3>() = -Jinv.transpose();
  }
  return res;
}

double accumulate_residuals(const std::vector<BoneResidual>& blocks, const DofLayout& layout, VecRef* grad,
                            MatRef* hess) {
  const bool assemble = layout.bones_dynamic && (grad || hess);
  if (grad && assemble)
    require(grad->size() == layout.size(), "skeletal term: gradient has ", grad->size(), " entries, expected ",
            layout.size());
  if (hess && assemble)
    require(hess->rows() == layout.size() && hess->cols() == layout.size(), "skeletal term: Hessian is ",
            hess->rows(), "x", hess->cols(), ", expected ", layout.size(), " square");
  double energy = 0.0;
  for (const BoneResidual& b : blocks) {
    const Vec3 Wr = b.W * b.r;
    energy += 0.5 * b.r.dot(Wr);
    if (!assemble) continue;
    for (int s = 0; s < 2; ++s) {
      if (b.bones[s] < 0) continue;
      const int os = layout.bone_offset(b.bones[s]);
      if (grad) grad->segment<6>(os) += b.J[s].transpose() * Wr;
      if (!hess) continue;
      const Eigen::Matrix<double, 6, 3> JtW = b.J[s].transpose() * b.W;
      for (int t = 0; t < 2; ++t) {
        if (b.bones[t] < 0) continue;
        hess->block<6, 6>(os, layout.bone_offset(b.bones[t])) += JtW * b.J[t];
      }
    }
  }
  return energy;
}

double BoneLeastSquaresTerm::compute(const StepContext& ctx, const Configuration& q, VecRef* grad, MatRef* hess) const {
  std::vector<BoneResidual> blocks;
  residuals(ctx, q, blocks);
  return accumulate_residuals(blocks, ctx.layout, grad, hess);
}

}  // namespace sflsh
