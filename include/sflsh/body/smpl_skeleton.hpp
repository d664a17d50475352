#pragma once
// SMPL's 24 joints: names, parents and order (DESIGN.md §3). Everything in
// sflsh that speaks of joints uses this order.
#include <array>
#include <string>
#include <string_view>

namespace sflsh {

inline constexpr int kSmplJoints = 24;
/// Pose-feature length: flattened (R_j - I) of joints 1..23 = 23 * 9.
inline constexpr int kSmplPoseFeatures = 207;

inline constexpr std::array<std::string_view, kSmplJoints> kSmplJointNames = {
    "pelvis",      "left_hip",      "right_hip",      "spine1",      "left_knee",   "right_knee",
    "spine2",      "left_ankle",    "right_ankle",    "spine3",      "left_foot",   "right_foot",
    "neck",        "left_collar",   "right_collar",   "head",        "left_shoulder", "right_shoulder",
    "left_elbow",  "right_elbow",   "left_wrist",     "right_wrist", "left_hand",   "right_hand"};

inline constexpr std::array<int, kSmplJoints> kSmplParents = {
    -1, 0, 0, 0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 9, 9, 12, 13, 14, 16, 17, 18, 19, 20, 21};

/// Index of a joint by SMPL name; throws sflsh::Error naming the unknown joint.
int smpl_joint_index(std::string_view name);

}  // namespace sflsh
