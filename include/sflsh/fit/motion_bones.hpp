#pragma once
// The prescribed bones of a motion, as `sflsh simulate --bones kinematic`
// drives an avatar with it (scene/simulation_run.hpp): target bones at every
// step t = s·h, and q_{−1}'s bones so that the run starts moving with the
// motion's velocity (or at rest).
#include "sflsh/asset/avatar.hpp"
#include "sflsh/fit/trajectory_sensitivity.hpp"
#include "sflsh/motion/motion_clip.hpp"

namespace sflsh {

/// Bones of `motion` on `avatar` at steps 0..steps of h (s), and before step 0.
BoneSequence motion_bones(const Avatar& avatar, const MotionClip& motion, double h, int steps, bool start_at_rest = false);

}  // namespace sflsh
