#pragma once
// AMASS motion files (.npz). Two key spellings are accepted:
//  - SMPL+H / SMPL style: `poses` (T by 156, T by 72, or any T by 3K with
//    K >= 22), `trans` (T by 3), `betas`, `gender`, `mocap_framerate`;
//  - SMPL-X style: `root_orient` (T by 3), `pose_body` (T by 63), `trans`,
//    `betas`, `gender`, `mocap_frame_rate`.
// Only body joints are used: the first 22 joints (pelvis..right_wrist), which
// SMPL+H and SMPL-X share with SMPL 0..21; SMPL's hand joints 22 and 23 stay at
// rest unless `poses` is T by 72 (plain SMPL).
//
// Axes: AMASS stores the world Z up, the body's root orientation already
// composed with it. SMPL models (and sflsh) are Y up, so the root rotation and
// the translation are pre-rotated by P = R_x(-90°) (which maps +Z to +Y):
// R_root' = P R_root and, since SMPL rotates the body about the rest pelvis
// J_0, trans' = P (trans + J_0) - J_0 (the pelvis lands at P times its AMASS
// position).
#include <string>

#include "sflsh/core/types.hpp"
#include "sflsh/motion/motion_clip.hpp"

namespace sflsh {

struct AmassInfo {
  std::string layout;        ///< "poses" or "root_orient+pose_body"
  std::string rate_key;      ///< the frame-rate key found
  int pose_columns = 0;      ///< columns of `poses` (72, 156, ...) or 66
  VecX betas;                ///< the file's shape (may be empty)
  std::string gender;        ///< "" when absent
};

/// Reads an AMASS .npz into an SMPL clip (Y up, see above). `rest_joints`
/// (24 by 3, metres; empty: default_smpl_rest_joints()) gives J_0 for the
/// axis change. Throws naming the file and the missing key or the key with the
/// wrong shape and the expected shape.
MotionClip read_amass(const std::string& path, const Points& rest_joints = Points(), AmassInfo* info = nullptr);

/// Writes `clip` as an AMASS-style SMPL .npz that read_amass reads back to the
/// same clip: `poses` (T by 72 axis-angle, root turned back to Z up), `trans`
/// (T by 3, metres, Z up), `mocap_framerate`, `gender` is not written.
/// Atomic: nothing half-written on failure.
void write_amass(const std::string& path, const MotionClip& clip, const Points& rest_joints = Points());

}  // namespace sflsh
