#pragma once
// A random-pose torture motion for stress runs: every `period`
// seconds each limited joint's target jumps to a new random local rotation
// inside its anatomical range (sim/joint_limits_table.hpp), so the skeleton is
// yanked across its whole range of motion again and again. The root stays at
// the origin with the rest orientation (a motion root for the pelvis error).
// Seeded and deterministic: the same seed gives the same clip on every
// platform (mt19937_64 and an explicit 53-bit mapping to [0, 1), not
// std::uniform_real_distribution, whose algorithm is implementation-defined).
//
// It lives in scene/ (not motion/) because the ranges are the simulator's
// (sim/); load_stress_motion() makes it available as "builtin:torture".
#include <cstdint>
#include <string>
#include <vector>

#include "sflsh/motion/load_motion.hpp"
#include "sflsh/motion/motion_clip.hpp"
#include "sflsh/sim/joint_limits_table.hpp"

namespace sflsh {

struct TortureOptions {
  double seconds = 10;     ///< clip length (s, > 0)
  double fps = 60;         ///< frames per second (> 0); a jump spans one frame, 1/fps s
  double period = 0.2;     ///< s between jumps (> 0, at least one frame)
  std::uint64_t seed = 1;  ///< random seed
  /// Share of each range used, centred in it (0, 1]: 1 = up to the limits.
  double range_fraction = 1.0;
};

/// The torture clip: frame i (time i/fps) holds pose k = floor(i/fps / period
/// + 1e-9); pose 0 is the rest pose (T-pose), poses k ≥ 1 draw every limited
/// joint's rotation vector θ_j = log(R_local) uniformly in the box [lower,
/// upper] of `ranges` (scaled by range_fraction about its centre), redrawn
/// while |θ_j| > 3 rad so that log(exp(θ)) = θ and the pose stays in the box.
/// Unlimited joints (the root) stay at rest, translation 0. `ranges` has one
/// entry per SMPL joint (24). Throws on bad options.
MotionClip torture_motion(const std::vector<JointRange>& ranges, const TortureOptions& options);

/// load_motion(spec, options, report), plus "builtin:torture" (torture_motion
/// with smpl_joint_ranges(), options.builtin_seconds and builtin_fps, seed 1,
/// then trimmed and sped up as MotionOptions asks). Other specs go to load_motion.
MotionClip load_stress_motion(const std::string& spec, const MotionOptions& options, MotionReport* report = nullptr);

}  // namespace sflsh
