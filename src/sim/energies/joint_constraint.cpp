#include "sflsh/sim/energies/joint_constraint.hpp"

#include <cmath>

#include "sflsh/core/error.hpp"

namespace sflsh {

JointConstraint::JointConstraint(const Avatar& avatar, double stiffness_ratio, double reference_mass)
    : joints_rest_(avatar.joints_rest), parents_(avatar.parents), ratio_(stiffness_ratio), mass_(reference_mass) {
  require(joints_rest_.rows() == Eigen::Index(parents_.size()), "JointConstraint: avatar has ", joints_rest_.rows(),
          " rest joints but ", parents_.size(), " parents");
  require(ratio_ > 0 && std::isfinite(ratio_), "JointConstraint: stiffness ratio must be positive, got ", ratio_);
  require(mass_ > 0 && std::isfinite(mass_), "JointConstraint: reference mass must be positive, got ", mass_);
}

void JointConstraint::residuals(const StepContext& ctx, const Configuration& q, std::vector<BoneResidual>& out) const {
  require(q.bones.size() == parents_.size(), "JointConstraint: configuration has ", q.bones.size(),
          " bones, expected ", parents_.size());
  require(ctx.h > 0, "JointConstraint: time step must be positive, got ", ctx.h);
  const Mat3 W = stiffness(ctx.h) * Mat3::Identity();
  for (std::size_t j = 0; j < parents_.size(); ++j) {
    const int p = parents_[j];
    if (p < 0) continue;
    const Vec3 Jbar = joints_rest_.row(j).transpose();
    const Vec3 x_child = q.bones[j] * Jbar;
    const Vec3 x_parent = q.bones[p] * Jbar;
    BoneResidual b;
    b.r = x_child - x_parent;
    b.W = W;
    b.bones = {int(j), p};
    b.J[0] = point_jacobian(x_child);
    b.J[1] = -point_jacobian(x_parent);
    out.push_back(b);
  }
}

}  // namespace sflsh
