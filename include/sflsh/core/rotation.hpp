#pragma once
// Rotations: axis-angle (SMPL/AMASS file boundary) <-> 3x3 matrices, and the
// SO(3) exponential map used to retract tangent-space steps.
#include "sflsh/core/types.hpp"

namespace sflsh {

/// Skew-symmetric matrix [w]x such that [w]x v = w × v.
Mat3 hat(const Vec3& w);

/// Rodrigues' formula: rotation matrix of the axis-angle vector `aa` (radians,
/// axis * angle). Exact and smooth near zero (Taylor branch below 1e-8 rad).
/// This is SMPL's `Rodrigues` and also the SO(3) exponential map.
Mat3 rodrigues(const Vec3& aa);

/// Inverse of rodrigues: axis-angle of rotation matrix R, angle in [0, pi].
Vec3 rotation_log(const Mat3& R);

}  // namespace sflsh
