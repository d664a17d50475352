#pragma once
// A motion expressed on SMPL's 24 joints: the interface every motion source
// (built-in motions, AMASS .npz, BVH, assimp formats) produces and the
// simulator consumes. Rotations are local (relative to the parent joint, in
// the SMPL rest frame), root translation in metres (world, Y up).
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "sflsh/body/body_model.hpp"

namespace sflsh {

struct MotionClip {
  std::string name;          ///< for messages ("builtin:jump", a file path)
  double fps = 30.0;         ///< frames per second of the samples below
  /// Per frame: 24 local joint rotations (unit quaternions, SMPL order).
  std::vector<std::vector<Eigen::Quaterniond>> rotations;
  /// Per frame: root (pelvis) translation, metres. Same convention as SMPL's
  /// `trans`/AMASS `trans`: added to the posed body.
  std::vector<Vec3> translations;
  /// Which SMPL joints the source actually drives (others stay at rest).
  std::vector<bool> joint_driven = std::vector<bool>(24, true);

  int num_frames() const { return int(rotations.size()); }
  double duration() const { return num_frames() > 1 ? (num_frames() - 1) / fps : 0.0; }

  /// Pose at time t (seconds, clamped to [0, duration]): slerp between
  /// neighbouring frames for rotations, linear for translation.
  BodyPose sample(double t) const;
};

}  // namespace sflsh
