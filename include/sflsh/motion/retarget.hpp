#pragma once
// Retargeting a source skeleton's animation (BVH, assimp) onto SMPL's 24
// joints.
//
// Rest-pose alignment: the source's rest pose and SMPL's T-pose differ per
// bone (CMU's rest has the legs splayed by ~20°, for instance). For a mapped
// SMPL joint j driven by source joint b,
//     S_j(t) = G_b(t) · W_b⁻¹ · C_j,
// where G_b is b's world rotation at frame t, W_b its world rotation in the
// source rest pose and C_j the smallest rotation taking SMPL's rest bone
// direction of j (towards its child) onto the source's rest bone direction
// (from b towards the joint mapped to that child). So S_j moves SMPL's bone
// exactly as the source moves its bone. SMPL local rotations are then
// L_j = S_parent(j)⁻¹ · S_j; rotations of unmapped source joints in between
// (CMU's LHipJoint, Neck1, ...) are thereby composed into the next mapped joint.
// Bone directions are aligned for the limb joints only (hips, knees, collars,
// shoulders, elbows, wrists), where rest poses differ in structure (splayed
// legs, A- vs T-pose arms). The pelvis uses C = I (the source's world axes are
// taken as SMPL's: Y up, facing +Z); the spine, neck, head, feet and hands
// inherit their parent's C: SMPL's joint placement there (the head joint in
// front of the neck, tilted spine segments) does not follow the anatomical
// axes, and matching those directions would bend the spine and tilt the head
// by up to ~40° even in the rest pose. Unmapped SMPL joints keep the identity
// local rotation.
#include <string>
#include <utility>
#include <vector>

#include "sflsh/core/types.hpp"
#include "sflsh/motion/motion_clip.hpp"
#include "sflsh/motion/skeleton_motion.hpp"

namespace sflsh {

/// Source joint name -> SMPL joint index.
struct JointMap {
  std::string name;  ///< "cmu", "mixamo" or the map file's path
  std::vector<std::pair<std::string, int>> entries;
};

/// Names of the built-in maps ("cmu": the CMU BVH converter's skeleton, 22
/// body joints: its finger joints carry marker noise of up to 170°, so SMPL's
/// hands stay at rest; "mixamo": Mixamo's 24, with or without the
/// "mixamorig:" prefix).
std::vector<std::string> builtin_joint_map_names();
/// A built-in map by name; throws listing the known ones.
JointMap builtin_joint_map(const std::string& name);
/// Reads a map file: one "source_name smpl_name" pair per line, '#' starts a
/// comment. Throws naming the file and line on unknown SMPL names, missing
/// fields and duplicates.
JointMap read_joint_map(const std::string& path);
/// The built-in map matching the most of `joint_names`.
JointMap best_builtin_joint_map(const std::vector<std::string>& joint_names);

/// SMPL rest joints (24 by 3, metres, T-pose, Y up) used when the caller has no
/// body model: an approximation of SMPL's neutral model at zero shape.
Points default_smpl_rest_joints();

/// Metres per file unit for "m", "cm", "mm", "inch" or "cmu" (the CMU BVH
/// converter's unit, 0.0254/0.45 m); throws on anything else ("auto" is
/// resolved by retarget_to_smpl).
double metres_per_unit(const std::string& units);

struct RetargetOptions {
  /// "auto" (the candidate making the source's leg length closest to the
  /// avatar's) or one of metres_per_unit's names.
  std::string units = "auto";
  /// 24 by 3 SMPL rest joints of the avatar (metres); empty: default_smpl_rest_joints().
  Points rest_joints;
  /// Root translation relative to the first frame (the clip starts at the
  /// avatar's rest placement). When false, the pelvis world position is the
  /// file's (scaled) root position: trans = k·p_root(t) − J_pelvis.
  bool root_from_start = true;
};

struct RetargetReport {
  std::string map_name;
  std::vector<std::string> mapped;   ///< "source -> smpl" per mapped joint
  std::vector<std::string> ignored;  ///< animated source joints not mapped
  std::vector<std::string> undriven; ///< SMPL joints no source joint drives
  std::string units;                 ///< resolved unit name
  double metres_per_unit = 1;
  /// Avatar size over the source's size in metres (leg length ratio, or height
  /// ratio when the legs are not mapped); root translation is multiplied by
  /// metres_per_unit * avatar_scale.
  double avatar_scale = 1;
};

/// The SMPL clip of `motion` under `map` (see the file comment). Throws when
/// the pelvis is not mapped (listing the file's joints and the names the map
/// expects) or when the map contradicts the file's hierarchy.
MotionClip retarget_to_smpl(const SkeletonMotion& motion, const JointMap& map, const RetargetOptions& options,
                            RetargetReport* report = nullptr);

}  // namespace sflsh
