#pragma once
// One sample of a teleoperated tool's pose: what a device (haptic arm, game
// controller, master arm) or a pose file gives the simulator at one instant.
#include <cmath>

#include <Eigen/Geometry>

#include "sflsh/core/types.hpp"

namespace sflsh::teleop {

/// The largest jaw opening angle a sample may carry (rad): pi, jaws flat open.
constexpr double kMaxClosure = 3.14159265358979323846;

struct PoseSample {
  double time = 0.0;  ///< seconds (device clock, pose-file clock or receive clock: see the producer)
  Vec3 position = Vec3::Zero();  ///< tool frame origin in world coordinates, metres
  /// Tool frame orientation (tool -> world), unit quaternion.
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();
  /// Gripper closure as the jaw opening angle in radians, in [0, pi]: 0 = jaws
  /// shut, larger = more open (a grasp happens when it drops below the scene's
  /// threshold). Tools without jaws send 0.
  double closure = 0.0;
};

/// Normalizes `q` unless its norm is already 1 to within 1e-15 (a unit
/// quaternion up to rounding). Renormalizing such a quaternion would only
/// shuffle its last bits, so a normalized quaternion written with 17 digits and
/// read back keeps its exact value: replays stay bit-identical.
inline void normalize_unless_unit(Eigen::Quaterniond& q) {
  if (std::abs(q.norm() - 1.0) > 1e-15) q.normalize();
}

}  // namespace sflsh::teleop
