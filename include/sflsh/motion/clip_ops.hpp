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

/// How far the first frame is from the second, compared with the rest of the
/// clip. Some BVH converters (the CMU "cgspeed" release among them) add a
/// T-pose as frame 1: the body then jumps from the T-pose into the motion
/// within one frame (1.4-2.4 rad at 120 fps on the CMU files, whose later
/// frame-to-frame changes stay below 0.42 rad).
struct FirstFrameJump {
  double angle = 0;          ///< largest local joint rotation between frames 0 and 1 (rad)
  int joint = -1;            ///< SMPL joint of that rotation (-1: fewer than 2 frames)
  double later_max = 0;      ///< largest one between any later neighbouring frames (rad)
  /// angle > 0.5 rad and angle > 2.5 later_max (needs at least 3 frames).
  bool discontinuous = false;
};
FirstFrameJump first_frame_jump(const MotionClip& clip);

/// Checks that the clip has frames, matching rotation/translation counts,
/// 24 unit quaternions per frame, finite values and fps > 0; throws naming the
/// clip, the frame and the joint otherwise.
void validate_clip(const MotionClip& clip);

}  // namespace sflsh
