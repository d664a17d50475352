#include "sflsh/scene/simulation_run.hpp"

#include "sflsh/scene/result_file.hpp"
#include "sflsh/scene/scene_run.hpp"
#include "sflsh/scene/scene_session.hpp"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>

#include "sflsh/core/error.hpp"
#include "sflsh/core/percentile.hpp"
#include "sflsh/sim/skeleton_pose.hpp"

namespace sflsh {

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

void SimulationResult::add_frame(FrameData fr) {
  frame_time.push_back(fr.time);
  frame_step_ms.push_back(fr.step_ms);
  frame_positions.push_back(std::move(fr.positions));
  frame_displacement.push_back(std::move(fr.displacement));
  frame_joints.push_back(std::move(fr.joints));
  frame_reduced.push_back(std::move(fr.reduced));
  frame_target_pelvis.push_back(fr.target_pelvis);
  for (size_t i = 0; i < fr.object_poses.size(); ++i) objects.at(i).poses.push_back(fr.object_poses[i]);
  for (size_t i = 0; i < fr.tools.size(); ++i) tools.at(i).frames.push_back(fr.tools[i]);
  for (size_t i = 0; i < fr.contacts.size(); ++i) contacts.at(i).frames.push_back(fr.contacts[i]);
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
  SceneSession scene(std::move(avatar), motion, options);
  SceneRunOptions ro;
  ro.progress = options.progress;
  ro.keep_frames = options.keep_frames;
  ro.on_frame = on_frame;
  ro.on_step = options.on_step;
  ro.resume = options.resume;
  ro.checkpoint = options.checkpoint;
  return run_scene(scene, ro);
}

}  // namespace sflsh
