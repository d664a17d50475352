#include "sflsh/teleop/pose_ramp.hpp"

#include <algorithm>
#include <cmath>

#include "sflsh/core/error.hpp"

namespace sflsh::teleop {

PoseRamp::PoseRamp(double t0, double duration, const Eigen::Isometry3d& tool_pose, const Eigen::Isometry3d& device_pose)
    : started_(true), t0_(t0), duration_(duration) {
  require(std::isfinite(t0), "pose ramp: start time ", t0, " s, expected finite");
  require(std::isfinite(duration) && duration >= 0, "pose ramp: duration ", duration, " s, expected >= 0");
  require(tool_pose.matrix().allFinite() && device_pose.matrix().allFinite(), "pose ramp: a pose is not finite");
  const Eigen::Isometry3d offset = tool_pose * device_pose.inverse();
  rotation_ = Eigen::Quaterniond(offset.linear()).normalized();
  translation_ = offset.translation();
}

double PoseRamp::progress(double t) const {
  if (!started_ || duration_ <= 0) return 1.0;
  const double u = std::clamp((t - t0_) / duration_, 0.0, 1.0);
  return u * u * (3.0 - 2.0 * u);
}

PoseSample PoseRamp::apply(const PoseSample& sample, double t) const {
  const double s = progress(t);
  if (s >= 1.0) return sample;
  const Eigen::Quaterniond R = rotation_.slerp(s, Eigen::Quaterniond::Identity());
  const Vec3 tr = (1.0 - s) * translation_;
  PoseSample out = sample;
  out.position = R * sample.position + tr;
  out.orientation = (R * sample.orientation).normalized();
  return out;
}

}  // namespace sflsh::teleop
