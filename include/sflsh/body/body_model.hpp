#pragma once
// An SMPL-format parametric body model: exactly SMPL's arrays and semantics
// (Loper et al. 2015; DESIGN.md §3). The model is immutable data; posing is a
// free function of (model, betas, pose, translation).
#include <string>
#include <vector>

#include <Eigen/Sparse>

#include "sflsh/core/body_pose.hpp"
#include "sflsh/core/types.hpp"

namespace sflsh {

struct BodyModel {
  /// #V by 3 template vertices (metres, Y up, T/A rest pose).
  Points v_template;
  /// #F by 3 faces, counter-clockwise seen from outside.
  Triangles faces;
  /// Shape directions: shapedirs[b] is #V by 3 (B entries; B may be 0).
  std::vector<Points> shapedirs;
  /// Pose directions: #V*3 by 207, row 3*v+c, multiplying the pose feature
  /// (flattened row-major (R_j - I) of joints 1..23). May be all zero, or
  /// empty (0 by 0) for "no pose blend shapes" (the readers store an all-zero
  /// file array so; it keeps posing a zero-posedirs model fast).
  MatX posedirs;
  /// 24 by #V joint regressor (sparse): J = J_regressor * v_shaped.
  Eigen::SparseMatrix<double, Eigen::RowMajor> J_regressor;
  /// #V by 24 linear-blend-skinning weights (rows sum to 1, non-negative).
  MatXr weights;
  /// Parent of each joint (-1 for the root); parents[j] < j.
  std::vector<int> parents;
  /// Joint names (SMPL's for SMPL-format models).
  std::vector<std::string> joint_names;
  /// Where it came from ("procedural" or a file path), for messages and hashes.
  std::string source;
  /// One line per shape direction saying what it means (may be empty).
  std::vector<std::string> shape_meanings;

  int num_vertices() const { return int(v_template.rows()); }
  int num_joints() const { return int(parents.size()); }
  int num_betas() const { return int(shapedirs.size()); }
  bool has_pose_blend_shapes() const;

  /// Checks array shapes against each other, index ranges, finiteness and the
  /// kinematic tree; throws sflsh::Error naming the offending array.
  void validate() const;
};

// BodyPose (core/body_pose.hpp): axis-angle per joint and root translation.

/// Result of the SMPL forward function.
struct PosedBody {
  Points v_shaped;        ///< #V by 3, template + shape blend shapes (unposed)
  Points joints_rest;     ///< 24 by 3, joints regressed from v_shaped (unposed)
  Points v_posed;         ///< #V by 3, after pose blend shapes + LBS + translation
  Points joints_posed;    ///< 24 by 3 posed joint positions (world)
  /// Per joint world rigid transform G_j (4x4) mapping unposed-shaped
  /// coordinates to posed: x_world = G_j * x_unposed (SMPL's A matrices).
  std::vector<Eigen::Matrix4d> joint_transforms;
};

/// v_template + Σ_b betas[b] * shapedirs[b]. `betas` may be shorter than B
/// (missing entries are 0); longer throws.
Points shape_vertices(const BodyModel& model, const VecX& betas);

/// J_regressor * v_shaped (24 by 3).
Points regress_joints(const BodyModel& model, const Points& v_shaped);

/// Pose feature (207): flattened row-major (R_j - I) for joints 1..23.
VecX pose_feature(const Points& axis_angle);

/// Per-joint world transforms G_j of the kinematic chain for rest joints
/// `joints_rest` and pose `pose` (SMPL's `with_zeros`/`pack` chain, with the
/// rest-joint subtraction so G_j maps unposed to posed points).
std::vector<Eigen::Matrix4d> joint_world_transforms(const BodyModel& model, const Points& joints_rest,
                                                    const BodyPose& pose);

/// The full SMPL forward function: shape, pose blend shapes, LBS, translation.
PosedBody pose_body(const BodyModel& model, const VecX& betas, const BodyPose& pose);

/// Named presets: "tpose" (all zero), "apose" (arms down ~45°), "walk" (a
/// mid-stride pose), "sit". Throws on an unknown name, listing the known ones.
BodyPose pose_preset(const std::string& name);

/// Parses "b0,b1,..." into a vector (throws naming the bad token).
VecX parse_betas(const std::string& csv);

}  // namespace sflsh
