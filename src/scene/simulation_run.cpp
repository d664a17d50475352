#include "sflsh/scene/simulation_run.hpp"

#include "sflsh/scene/result_file.hpp"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <limits>
#include <sstream>

#include "sflsh/core/error.hpp"
#include "sflsh/core/interrupt.hpp"
#include "sflsh/core/percentile.hpp"
#include "sflsh/core/progress.hpp"
#include "sflsh/sim/finite_guard.hpp"
#include "sflsh/sim/skeleton_pose.hpp"
#include "sflsh/sim/state_file.hpp"

namespace sflsh {
namespace {

bool finite_configuration(const std::vector<Isometry>& bones) {
  for (const auto& b : bones)
    if (!b.matrix().allFinite()) return false;
  return true;
}

// World position of SMPL joint 0 (the pelvis) under bone transforms `bones`:
// G_0 J̄_0, as joint_world_positions() and the result's /frames/joints put it.
Vec3 pelvis_position(const Avatar& avatar, const std::vector<Isometry>& bones) {
  return bones[0] * Vec3(avatar.joints_rest.row(0).transpose());
}

}  // namespace

void SimulationResult::add_step_times(const StepReport& rep) {
  // By name, in order of first appearance: terms may come and go between steps.
  auto add = [&](const std::string& name, double ms) {
    const auto it = std::find(part_names.begin(), part_names.end(), name);
    if (it != part_names.end()) {
      part_ms[it - part_names.begin()] += ms;
    } else {
      part_names.push_back(name);
      part_ms.push_back(ms);
    }
  };
  for (const TermEnergy& e : rep.energies) add(e.name, e.ms);
  add("solve", rep.ms_solve);
}

void SimulationResult::add_step(double t, const StepReport& rep) {
  step_time.push_back(t);
  step_energy.push_back(rep.energy_after);
  step_grad_norm.push_back(rep.grad_norm_before);
  step_decrement.push_back(rep.newton_decrement);
  step_outcome.push_back(int(rep.outcome));
  step_ms.push_back(rep.ms_total);
  add_step_times(rep);
  accepted += rep.accepted;
  damped += rep.damped;
  rejected += rep.rejected;
}

double SimulationResult::median_step_ms() const { return percentile(step_ms, 0.5); }
double SimulationResult::p95_step_ms() const { return percentile(step_ms, 0.95); }

std::string SimulationResult::describe() const {
  std::ostringstream o;
  o << std::fixed << std::setprecision(3);
  o << "simulated " << (step_time.empty() ? 0.0 : step_time.back()) << " s of " << motion << " on " << avatar << ": "
    << step_time.size() << " steps of " << dt * 1e3 << " ms (bones " << (bones_dynamic ? "dynamic" : "kinematic")
    << ", " << newton_iters << " Newton iteration(s) per step), " << num_frames << " frames\n"
    << "steps: " << accepted << " accepted, " << damped << " damped, " << rejected << " rejected; step time median "
    << median_step_ms() << " ms, p95 " << p95_step_ms() << " ms\n";
  if (!part_names.empty() && !step_ms.empty()) {
    o << "mean ms per step:";
    for (size_t i = 0; i < part_names.size(); ++i)
      o << (i ? ", " : " ") << part_names[i] << " " << part_ms[i] / double(step_ms.size());
    o << "\n";
  }
  if (incomplete) o << "INCOMPLETE: the run stopped early: " << stop_reason << "\n";
  if (pelvis_frames > 0)
    o << std::setprecision(1) << "pelvis vs motion root: mean " << pelvis_error_mean * 1e3 << " mm, max "
      << pelvis_error_max * 1e3 << " mm over " << pelvis_frames << " frames\n";
  o << describe_scene_parts(*this);
  return o.str();
}

std::vector<Isometry> target_bones(const Avatar& avatar, const BodyPose& pose) {
  return bone_transforms_from_pose(avatar.joints_rest, avatar.parents, pose);
}

long run_step_count(const MotionClip& motion, const RunOptions& options) {
  const double seconds = options.seconds > 0 ? options.seconds : motion.duration();
  return std::max(1L, long(std::llround(seconds / options.sim.h)));
}

SimulationResult run_simulation(std::shared_ptr<const Avatar> avatar, const MotionClip& motion, const RunOptions& options,
                                const std::function<void(const FrameData&)>& on_frame) {
  require(motion.num_frames() > 0, motion.name, ": motion has no frames");
  const double h = options.sim.h;
  require(h > 0 && std::isfinite(h), "time step must be positive, got ", h);
  require(options.output_fps > 0, "--output-fps must be positive, got ", options.output_fps);
  require(options.seconds > 0 || motion.duration() > 0, motion.name, ": motion lasts 0 s; give a duration");
  const long steps = run_step_count(motion, options);

  Simulator sim(avatar_model(avatar, options.sim, options.sim.bones_dynamic ? &options.skeleton : nullptr));
  std::vector<Isometry> targets = target_bones(*avatar, motion.sample(0.0));
  if (options.start_at_rest) {
    sim.reset(targets);
  } else {
    // Start moving with the motion: q_{-1} = Δ⁻¹ q_0 with Δ = G(h) G(0)⁻¹ the
    // first step's motion of each bone, so (q_0 − q_{-1})/h is the motion's
    // velocity. Mocap clips start mid-motion (a run at 3-4 m/s); from rest
    // the tracking springs needed ~0.3 s and up to 4 cm to catch up.
    const std::vector<Isometry> next = target_bones(*avatar, motion.sample(h));
    Configuration q0, q_prev;
    q0.bones = targets;
    q0.z = VecX::Zero(avatar->num_reduced());
    q_prev.z = q0.z;
    q_prev.bones = bones_one_step_before(targets, next);
    sim.reset(q0, q_prev);
  }

  long first_step = 0;
  if (!options.resume.empty()) {
    sim.set_state(read_state(options.resume, sim.model()));
    first_step = std::lround(sim.time() / h);
    require(std::abs(sim.time() - first_step * h) <= 1e-9 * std::max(1.0, sim.time()), options.resume,
            ": the checkpoint's time ", sim.time(), " s is not a whole number of steps of ", h, " s");
    require(first_step <= steps, options.resume, ": the checkpoint is at ", sim.time(),
            " s, past the run's end at ", steps * h, " s");
    targets = target_bones(*avatar, motion.sample(sim.time()));
  }

  SimulationResult r;
  r.motion = motion.name;
  r.dt = h;
  r.bones_dynamic = options.sim.bones_dynamic;
  r.newton_iters = options.sim.newton.iterations;
  r.faces = avatar->surface_faces;
  r.surface_rest = avatar->surface_rest;
  double pelvis_error_sum = 0;
  // `targets` holds the target bones at time t.
  auto record_frame = [&](double t, double ms) {
    FrameData fr{t, ms, sim.posed_surface(), sim.soft_displacement(), sim.joints(), sim.state().z,
                 pelvis_position(*avatar, targets)};
    const double pelvis_error = (fr.joints.row(0).transpose() - fr.target_pelvis).norm();
    pelvis_error_sum += pelvis_error;
    r.pelvis_error_max = std::max(r.pelvis_error_max, pelvis_error);
    ++r.pelvis_frames;
    r.pelvis_error_mean = pelvis_error_sum / r.pelvis_frames;
    ++r.num_frames;
    if (on_frame) on_frame(fr);
    if (!options.keep_frames) return;
    r.frame_time.push_back(t);
    r.frame_step_ms.push_back(ms);
    r.frame_positions.push_back(std::move(fr.positions));
    r.frame_displacement.push_back(std::move(fr.displacement));
    r.frame_joints.push_back(std::move(fr.joints));
    r.frame_reduced.push_back(std::move(fr.reduced));
    r.frame_target_pelvis.push_back(fr.target_pelvis);
  };
  record_frame(sim.time(), 0.0);

  const double frame_dt = 1.0 / options.output_fps;
  double next_frame = (std::floor(sim.time() / frame_dt + 1e-9) + 1) * frame_dt, ms_since_frame = 0;
  int steps_since_frame = 0;
  Progress progress("simulating " + motion.name, steps);
  for (long s = first_step; s < steps; ++s) {
    if (interrupt_signal()) throw_if_interrupted("at step " + std::to_string(s + 1) + " of " + std::to_string(steps));
    const double t = (s + 1) * h;
    const BodyPose pose = motion.sample(t);
    targets = target_bones(*avatar, pose);
    if (s + 1 == options.inject_nan_at_step)  // test only: a NaN target bone (the pose terms check their own input)
      targets[0].translation().x() = std::numeric_limits<double>::quiet_NaN();
    auto stop = [&](const std::string& why) {
      if (options.progress) progress.finish();
      r.incomplete = true;
      r.stop_reason = why;
      throw SimulationStopped(why, std::move(r));
    };
    StepReport rep;
    try {
      rep = sim.step(targets, pose);
      require_finite_step(sim.model(), sim.scene_state(), rep, s + 1, motion.name);
    } catch (const NonFiniteError& e) {
      stop(e.what());
    } catch (const Error& e) {
      // The Newton step refuses a non-finite configuration itself (before any term is named).
      if (finite_configuration(targets)) throw;
      std::ostringstream why;
      why << motion.name << ": non-finite value at step " << s + 1 << " (t = " << t << " s): body '"
          << sim.model().bodies().at(0).name << "': a target bone is not finite (" << e.what() << "); stopped";
      stop(why.str());
    }
    r.add_step(t, rep);
    ms_since_frame += rep.ms_total;
    ++steps_since_frame;
    if (options.on_step) options.on_step(sim, rep);
    if (t + 1e-9 >= next_frame) {
      record_frame(t, ms_since_frame / steps_since_frame);
      next_frame += frame_dt;
      ms_since_frame = 0;
      steps_since_frame = 0;
    }
    if (options.progress) progress.update(s + 1);
  }
  if (options.progress) progress.finish();
  if (!options.checkpoint.empty()) write_state(options.checkpoint, sim.model(), sim.scene_state());
  return r;
}

}  // namespace sflsh
