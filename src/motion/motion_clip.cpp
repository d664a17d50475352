#include "sflsh/motion/motion_clip.hpp"

#include "sflsh/body/smpl_skeleton.hpp"
#include "sflsh/motion/clip_ops.hpp"

namespace sflsh {

BodyPose MotionClip::sample(double t) const {
  std::vector<Eigen::Quaterniond> q;
  BodyPose pose;
  interpolate_frame(*this, t, &q, &pose.translation);
  for (int j = 0; j < kSmplJoints; ++j) pose.axis_angle.row(j) = axis_angle_from_quaternion(q[j]).transpose();
  return pose;
}

}  // namespace sflsh
