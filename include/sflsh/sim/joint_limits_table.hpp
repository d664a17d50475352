#pragma once
// Anatomical ranges of SMPL's 24 joints, as bounds on the components of the
// local rotation vector θ_j = log(R_parentᵀ R_j) (radians), expressed in
// SMPL's rest frame: x = the body's left, y = up, z = forward (DESIGN.md §3).
// For the moderate angles of joints these components behave like Euler
// angles about the three axes; the bounds are deliberately generous (a soft
// limit for implausible poses, not a clinical range). Sources for the
// magnitudes: AAOS normal ranges of motion (Greene & Heckman 1994), e.g. hip
// flexion ~120°, knee flexion ~150°, elbow flexion ~150°.
//
// Signs (left side; the right side is the mirror image x → x, y → −y, z → −z):
//   hip:      flexion (thigh forward) = −x, abduction (thigh out) = +z
//   knee:     flexion (shin back)     = +x, one way only
//   ankle:    plantar flexion (toes down) = +x
//   spine/neck/head: flexion (forward) = +x
//   shoulder: arm up = +z, arm forward = −y
//   elbow:    flexion (forearm forward) = −y, one way only
//   wrist/hand: flexion (palm down, T-pose) = −z
#include <vector>

#include "sflsh/core/types.hpp"

namespace sflsh {

/// Range of one joint's local rotation vector components (radians).
struct JointRange {
  bool limited = false;  ///< false: free (the root)
  Vec3 lower = Vec3::Zero();
  Vec3 upper = Vec3::Zero();
};

/// Default ranges for SMPL's 24 joints in SMPL order (root unlimited).
const std::vector<JointRange>& smpl_joint_ranges();

}  // namespace sflsh
