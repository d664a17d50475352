#include "sflsh/fit/motion_bones.hpp"

#include <cmath>

#include "sflsh/core/error.hpp"
#include "sflsh/scene/simulation_run.hpp"
#include "sflsh/sim/skeleton_pose.hpp"

namespace sflsh {

BoneSequence motion_bones(const Avatar& avatar, const MotionClip& motion, double h, int steps, bool start_at_rest) {
  require(h > 0 && steps >= 0, "motion_bones: need h > 0 and steps >= 0");
  BoneSequence seq;
  seq.h = h;
  for (int s = 0; s <= steps; ++s) seq.bones.push_back(target_bones(avatar, motion.sample(s * h)));
  if (start_at_rest) {
    seq.bones_before = seq.bones[0];
  } else {
    // As a run starts moving (CompiledBody::initial_state): q_{-1} = Δ⁻¹ q_0 with Δ = G(h) G(0)⁻¹ per bone.
    const std::vector<Isometry> next = target_bones(avatar, motion.sample(h));
    seq.bones_before = bones_one_step_before(seq.bones[0], next);
  }
  return seq;
}

BoneSequence observed_bones(const Observations& obs, double h, int steps) {
  require(obs.start_bones.size() == 2 && !obs.step_bones.empty(), obs.path, ": holds no bones of its run");
  require(obs.dt > 0 && std::abs(obs.dt - h) <= 1e-9 * h, obs.path, ": its run's bones are per step of ", obs.dt,
          " s (/meta/dt), but the fit steps by ", h, " s (give --dt ", obs.dt, ")");
  require(steps >= 0 && steps <= int(obs.step_bones.size()), obs.path, ": holds the bones of ", obs.step_bones.size(),
          " steps, the observations need ", steps);
  BoneSequence seq;
  seq.h = h;
  seq.bones_before = obs.start_bones[0];
  seq.bones.push_back(obs.start_bones[1]);
  for (int s = 0; s < steps; ++s) seq.bones.push_back(obs.step_bones[size_t(s)]);
  return seq;
}

}  // namespace sflsh
