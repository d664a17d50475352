#include "sflsh/sim/energies/joint_limit.hpp"

#include <cmath>

#include "sflsh/core/error.hpp"
#include "sflsh/core/rotation.hpp"
#include "sflsh/sim/skeleton_pose.hpp"

namespace sflsh {

JointLimit::JointLimit(const Avatar& avatar, std::vector<JointRange> ranges, std::vector<double> stiffness)
    : parents_(avatar.parents), ranges_(std::move(ranges)), stiffness_(std::move(stiffness)) {
  require(ranges_.size() == parents_.size() && stiffness_.size() == parents_.size(), "JointLimit: ", ranges_.size(),
          " ranges and ", stiffness_.size(), " stiffnesses for ", parents_.size(), " joints");
  for (std::size_t j = 0; j < parents_.size(); ++j) {
    require(stiffness_[j] >= 0 && std::isfinite(stiffness_[j]), "JointLimit: joint ", j,
            " stiffness must be >= 0, got ", stiffness_[j]);
    require(!ranges_[j].limited || (ranges_[j].lower.array() <= ranges_[j].upper.array()).all(), "JointLimit: joint ",
            j, " has lower bound above upper bound");
    require(!ranges_[j].limited || parents_[j] >= 0, "JointLimit: the root joint ", j, " cannot be limited");
  }
}

void JointLimit::residuals(const StepContext& ctx, const Configuration& q, std::vector<BoneResidual>& out) const {
  require(q.bones.size() == parents_.size(), "JointLimit: configuration has ", q.bones.size(), " bones, expected ",
          parents_.size());
  for (std::size_t j = 0; j < parents_.size(); ++j) {
    const JointRange& range = ranges_[j];
    if (!range.limited || stiffness_[j] == 0.0) continue;
    const Vec3 theta = rotation_log(local_rotation(q.bones, parents_, int(j)));
    const Vec3 excess = theta - theta.cwiseMax(range.lower).cwiseMin(range.upper);
    if (excess.isZero(0.0)) continue;  // inside the range: no energy, no derivatives
    const int p = parents_[j];
    const Mat3 dtheta = so3_left_jacobian_inverse(theta) * q.bones[p].linear().transpose();
    BoneResidual b;
    b.r = excess;
    b.W = stiffness_[j] * Mat3::Identity();
    b.bones = {int(j), p};
    for (int a = 0; a < 3; ++a) {
      if (excess[a] == 0.0) continue;  // clamped axis: the residual is constant there
      b.J[0].block<1, 3>(a, 0) = dtheta.row(a);
      b.J[1].block<1, 3>(a, 0) = -dtheta.row(a);
    }
    out.push_back(b);
  }
}

}  // namespace sflsh
