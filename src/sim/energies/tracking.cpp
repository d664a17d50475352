#include "sflsh/sim/energies/tracking.hpp"

#include <cmath>

#include "sflsh/core/error.hpp"
#include "sflsh/core/rotation.hpp"

namespace sflsh {

Tracking::Tracking(const Avatar& avatar, std::vector<double> rotation_stiffness, double position_stiffness,
                   double position_force_limit)
    : joints_rest_(avatar.joints_rest),
      parents_(avatar.parents),
      k_rot_(std::move(rotation_stiffness)),
      k_pos_(position_stiffness),
      force_limit_(position_force_limit) {
  require(force_limit_ >= 0 && std::isfinite(force_limit_), "Tracking: root force limit must be >= 0 N, got ",
          force_limit_);
  require(joints_rest_.rows() == Eigen::Index(parents_.size()) && !parents_.empty() && parents_[0] < 0,
          "Tracking: avatar needs a skeleton with root joint 0 (", joints_rest_.rows(), " rest joints, ",
          parents_.size(), " parents)");
  require(k_rot_.size() == parents_.size(), "Tracking: ", k_rot_.size(), " rotation stiffnesses for ",
          parents_.size(), " joints");
  for (std::size_t j = 0; j < k_rot_.size(); ++j)
    require(k_rot_[j] >= 0 && std::isfinite(k_rot_[j]), "Tracking: joint ", j, " stiffness must be >= 0, got ",
            k_rot_[j]);
  require(k_pos_ >= 0 && std::isfinite(k_pos_), "Tracking: root position stiffness must be >= 0, got ", k_pos_);
}

void Tracking::residuals(const StepContext& ctx, const Configuration& q, std::vector<BoneResidual>& out) const {
  const int J = int(parents_.size());
  require(int(q.bones.size()) == J, "Tracking: configuration has ", q.bones.size(), " bones, expected ", J);
  require(ctx.target_pose.axis_angle.rows() == J && ctx.target_pose.axis_angle.allFinite() &&
              ctx.target_pose.translation.allFinite(),
          "Tracking: target pose must be finite with ", J, " joint rotations, got ",
          ctx.target_pose.axis_angle.rows());
  for (int j = 0; j < J; ++j) {
    if (k_rot_[j] == 0.0) continue;
    const Mat3 T = rodrigues(ctx.target_pose.axis_angle.row(j).transpose());
    out.push_back(rotation_residual(q, j, T.transpose(), parents_[j], k_rot_[j] * Mat3::Identity()));
  }
  if (k_pos_ > 0 && force_limit_ == 0) {
    const Vec3 root = joints_rest_.row(0).transpose();
    const Vec3 x = q.bones[0] * root;
    BoneResidual b;
    b.r = x - (root + ctx.target_pose.translation);
    b.W = k_pos_ * Mat3::Identity();
    b.bones[0] = 0;
    b.J[0] = point_jacobian(x);
    out.push_back(b);
  }
}

double Tracking::compute(const StepContext& ctx, const Configuration& q, VecRef* grad, MatRef* hess) const {
  double E = BoneLeastSquaresTerm::compute(ctx, q, grad, hess);
  if (k_pos_ == 0 || force_limit_ == 0) return E;
  // The Huber root spring on the horizontal part of r, a plain spring along
  // gravity (header comment).
  const Vec3 root = joints_rest_.row(0).transpose();
  const Vec3 x = q.bones[0] * root;
  const Vec3 r = x - (root + ctx.target_pose.translation);
  const Vec3 up = ctx.gravity.squaredNorm() > 0 ? Vec3(ctx.gravity.normalized()) : Vec3::Zero();
  const Mat3 V = up * up.transpose();  // projector on the vertical
  const Vec3 rv = V * r, rh = r - rv;
  const double n = rh.norm(), d = force_limit_ / k_pos_;
  const bool inner = n <= d;
  E += 0.5 * k_pos_ * rv.squaredNorm() + (inner ? 0.5 * k_pos_ * n * n : force_limit_ * (n - 0.5 * d));
  if (!ctx.layout.bones_dynamic) return E;
  const Mat36 J = point_jacobian(x);
  const double w = inner ? k_pos_ : force_limit_ / n;  // ∂E/∂r_h = w r_h
  const int o = ctx.layout.bone_offset(0);
  if (grad) grad->segment<6>(o) += J.transpose() * (k_pos_ * rv + w * rh);
  if (hess) hess->block<6, 6>(o, o) += J.transpose() * (k_pos_ * V + w * (Mat3::Identity() - V)) * J;
  return E;
}

}  // namespace sflsh
