#pragma once
// An SMPL pose: 24 joint rotations (axis-angle, rad, each relative to its
// parent; row 0 = the pelvis' global orientation) and the root translation
// (m, world). A plain value shared by the body model, motions and the runtime.
#include "sflsh/core/types.hpp"

namespace sflsh {

struct BodyPose {
  Points axis_angle = Points::Zero(24, 3);  ///< 24 by 3, rad
  Vec3 translation = Vec3::Zero();          ///< m, world
};

}  // namespace sflsh
