#pragma once
// A source skeleton's animation in a format-independent form (what BVH and
// assimp files are converted to before retargeting to SMPL): a joint tree with
// rest local transforms and, per frame, local rotations and translations.
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "sflsh/core/types.hpp"
#include "sflsh/motion/bvh.hpp"

namespace sflsh {

struct SkeletonMotion {
  std::string source;                              ///< file path, for messages
  std::vector<std::string> names;                  ///< #J joint names
  std::vector<int> parents;                        ///< #J, parents[j] < j, -1 for roots
  std::vector<Eigen::Quaterniond> rest_rotations;  ///< #J local rest rotations
  std::vector<Vec3> rest_translations;             ///< #J local rest translations (file units)
  std::vector<double> scales;                      ///< #J uniform local scales (1 unless the file says)
  std::vector<bool> animated;                      ///< #J: the file carries keys for the joint
  double fps = 0;                                  ///< frames per second
  int num_frames = 0;
  std::vector<Eigen::Quaterniond> rotations;       ///< #frames by #J local rotations (row-major)
  std::vector<Vec3> translations;                  ///< #frames by #J local translations (file units)

  int num_joints() const { return int(names.size()); }
  /// Index of the joint named `name`, -1 if absent.
  int find(const std::string& name) const;
};

/// World rotations (#J) and positions (#J, file units) by forward kinematics
/// at `frame`, or of the rest pose when frame < 0. Uniform scales multiply the
/// child translations: p_j = p_parent + c_parent R_parent t_j.
void skeleton_world_pose(const SkeletonMotion& motion, int frame, std::vector<Eigen::Quaterniond>* rotations,
                         std::vector<Vec3>* positions);

/// Converts a parsed BVH: joints in file order, then one extra joint
/// "<joint>_End" per End Site (not animated); rest rotations are identity.
SkeletonMotion skeleton_motion_from_bvh(const BvhMotion& bvh);

}  // namespace sflsh
