#pragma once
// Conversions between the skeleton's DoFs — 24 bone transforms G_i
// (configuration.hpp) — and the SMPL pose θ (local axis-angle + root
// translation). Seed §3: "We can obtain the SMPL pose θ by extracting the
// skeleton root transformation and the joint angles from the {φ_i}".
//
// Convention (SMPL, body_model.hpp): G_j maps unposed points to world,
//   G_j = [R_j | t_j],  R_j = R_parent · rodrigues(θ_j),  R_0 = rodrigues(θ_0),
// and the root joint sits at J̄_0 + translation. When the bones are not
// exactly connected (penalty joint constraints), θ is read from rotations
// only; joint positions come from each joint's own bone.
#include <vector>

#include "sflsh/body/body_model.hpp"
#include "sflsh/sim/configuration.hpp"

namespace sflsh {

/// Bone transforms G_j (#J) of the kinematic tree `parents` (#J, parents[j] < j)
/// with rest joints `joints_rest` (#J by 3, m, unposed) in pose `pose`
/// (SMPL's chain, body_model.hpp's joint_world_transforms, translation included).
std::vector<Isometry> bone_transforms_from_pose(const Points& joints_rest, const std::vector<int>& parents,
                                                const BodyPose& pose);

/// SMPL pose of bone transforms `bones` (#J): θ_j = log(R_parentᵀ R_j)
/// (radians, root: log R_0) and translation = G_0 J̄_0 − J̄_0 (m).
BodyPose pose_from_bone_transforms(const std::vector<Isometry>& bones, const Points& joints_rest,
                                   const std::vector<int>& parents);

/// Local rotation of joint j relative to its parent, R_parentᵀ R_j (R_0 for the root).
Mat3 local_rotation(const std::vector<Isometry>& bones, const std::vector<int>& parents, int j);

/// #J by 3 world joint positions, row j = G_j J̄_j (m): where bone j puts its
/// own joint (its parent's bone puts it at G_parent J̄_j; the joint
/// constraint makes the two agree).
Points joint_world_positions(const std::vector<Isometry>& bones, const Points& joints_rest);

/// Starting a run moving with a motion: the bones one step before its first
/// frame, q_{−1} = Δ⁻¹ q_0 per bone with Δ = G(h) G(0)⁻¹ the first step's
/// motion, i.e. G(0) G(h)⁻¹ G(0), so that (q_0 − q_{−1})/h is the motion's
/// velocity (backward Euler's inertia then carries the body on). `at_start`:
/// G(0); `after_one_step`: G(h); the same length (throws otherwise).
std::vector<Isometry> bones_one_step_before(const std::vector<Isometry>& at_start,
                                            const std::vector<Isometry>& after_one_step);

}  // namespace sflsh
