#pragma once
// Operations on SMPL motion clips: interpolation, resampling to another rate,
// trimming and speed change. Rotations are interpolated with slerp (shortest
// arc), root translations linearly.
#include <vector>

#include <Eigen/Geometry>

#include "sflsh/core/types.hpp"
#include "sflsh/motion/motion_clip.hpp"

namespace sflsh {

/// Interpolated frame of `clip` at time `t` (seconds, clamped to
/// [0, duration]): 24 local rotations (slerp between the neighbouring frames)
/// and the root translation (linear, metres). Throws on an empty clip.
void interpolate_frame(const MotionClip& clip, double t, std::vector<Eigen::Quaterniond>* rotations,
                       Vec3* translation);

/// The clip sampled at `fps` frames per second over its whole duration
/// (frame i at time i / fps; the last frame lies at or before the end).
MotionClip resample(const MotionClip& clip, double fps);

/// The part of the clip between `start_s` and `end_s` (seconds; `end_s` < 0
/// means the end), re-timed to start at 0, at the clip's rate. Throws when the
/// interval is empty or starts after the end.
MotionClip trim(const MotionClip& clip, double start_s, double end_s);

/// The clip played `speed` times faster (> 0): same frames, fps * speed.
MotionClip change_speed(const MotionClip& clip, double speed);

/// SMPL pose parameters of every frame: #T by 72 axis-angle (radians, joint
/// j in columns 3j..3j+2) and #T by 3 root translations (metres).
void clip_to_smpl_params(const MotionClip& clip, MatXr* poses, MatXr* trans);

/// Unit quaternion of an axis-angle vector (radians).
Eigen::Quaterniond quaternion_from_axis_angle(const Vec3& aa);
/// Axis-angle (angle in [0, pi]) of a unit quaternion.
Vec3 axis_angle_from_quaternion(const Eigen::Quaterniond& q);

/// Checks that the clip has frames, matching rotation/translation counts,
/// 24 unit quaternions per frame, finite values and fps > 0; throws naming the
/// clip, the frame and the joint otherwise.
void validate_clip(const MotionClip& clip);

}  // namespace sflsh
