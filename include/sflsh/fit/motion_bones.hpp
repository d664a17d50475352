#pragma once
// The prescribed bones of a motion, as `sflsh simulate --bones kinematic`
// drives an avatar with it (scene/simulation_run.hpp): target bones at every
// step t = s·h, and q_{−1}'s bones so that the run starts moving with the
// motion's velocity (or at rest); or the bones an observed run had.
#include "sflsh/asset/avatar.hpp"
#include "sflsh/fit/observations.hpp"
#include "sflsh/fit/trajectory_sensitivity.hpp"
#include "sflsh/motion/motion_clip.hpp"

namespace sflsh {

/// Bones of `motion` on `avatar` at steps 0..steps of h (s), and before step 0.
BoneSequence motion_bones(const Avatar& avatar, const MotionClip& motion, double h, int steps, bool start_at_rest = false);

/// The bones an observed run had (Observations::start_bones, step_bones: a
/// run with dynamic bones, whose bones are not the motion's) at steps 0..steps
/// of h. Throws one line naming the file when it holds fewer steps or its
/// time step (/meta/dt) is not h.
BoneSequence observed_bones(const Observations& obs, double h, int steps);

}  // namespace sflsh
