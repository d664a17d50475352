#pragma once
// Bringing a tool to a live device without a kick.
//
// When a live device takes over a tool that already has a pose (its keyframes,
// its pose file, a coupled body at rest), the device is rarely where the tool
// is: a 1 cm offset through a 2e4 N/m coupling, or a kinematic probe moved 1 cm
// into the flesh in one step, is a force step of ~100 N on the operator's hand.
// A PoseRamp starts at the offset O = T0 D0⁻¹ between the tool's pose T0 and
// the device's first pose D0 and fades it out over `duration` seconds:
//   P(t) = O(s) D(t),  O(s) = (slerp(R_O, I, s), (1 − s) t_O),
//   s = smoothstep((t − t0) / duration) = 3u² − 2u³,
// so the commanded pose starts at the tool (no jump), ends on the device
// (s = 1 after `duration`), and its velocity is continuous at both ends.
#include <Eigen/Geometry>

#include "sflsh/core/types.hpp"
#include "sflsh/teleop/pose_sample.hpp"

namespace sflsh::teleop {

class PoseRamp {
 public:
  /// Not started: apply() returns its sample unchanged.
  PoseRamp() = default;
  /// Starts at time `t0` (s): the tool is at `tool_pose`, the device's first
  /// sample is at `device_pose` (world). `duration` ≥ 0 s (0: no ramp).
  PoseRamp(double t0, double duration, const Eigen::Isometry3d& tool_pose, const Eigen::Isometry3d& device_pose);

  bool started() const { return started_; }
  /// Whether the ramp still moves the pose at time `t` (s).
  bool active(double t) const { return started_ && progress(t) < 1.0; }
  /// s(t) in [0, 1] (1 when not started).
  double progress(double t) const;
  /// The commanded sample at time `t`: the device's `sample` moved by O(s(t)).
  /// The closure and the time stay the device's.
  PoseSample apply(const PoseSample& sample, double t) const;

 private:
  bool started_ = false;
  double t0_ = 0, duration_ = 0;
  Eigen::Quaterniond rotation_ = Eigen::Quaterniond::Identity();  ///< R_O
  Vec3 translation_ = Vec3::Zero();                               ///< t_O
};

}  // namespace sflsh::teleop
