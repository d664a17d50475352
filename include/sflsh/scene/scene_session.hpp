#pragma once
// A scene advanced one step at a time: the SceneDescription
// (scene_description.hpp) becomes a Model — bodies with their soft-tissue and
// skeleton terms, dynamic rigid objects as 6-DoF bodies, tools, and only the
// contact terms the scene's pairs need — and a State, stepped with StepInputs
// that carry each body's motion targets, the static and kinematic objects and
// tools as world frames and the tools' grasps as anchored points (by the ids
// the compiler registered).
//
// The session is a facade: compile_scene (scene_compiler.hpp) makes the Model,
// the initial State and the bodies', objects' and tools' constant parts; one
// ToolDriver per tool (tool_driver.hpp) runs its pose source, jaws, grasps and
// feedback; the session steps them together.
//
// `sflsh simulate scene.yaml` (run_scene, scene_run.hpp) steps it as fast as
// it can and records frames; `sflsh run scene.yaml --realtime` steps it in
// time with the wall clock; the browser viewer pushes device poses into it.
//
// Scene conventions (documented for users in scene_description.hpp):
//   * placement P (offset, heading about +Y) is applied to the motion: the
//     body's targets are P·G(t); with a non-zero `velocity` the placement
//     travels, P(t) = T(velocity·t)·P, and the body starts with that velocity;
//   * a body without a motion holds its rest pose with its joint springs but
//     its root is free (it falls, rolls and comes to rest under contact);
//   * bodies that collide with another body track their motion's root with a
//     force limit (body_push_limit × body weight) so that contact, not the
//     motion, decides where they meet;
//   * tools follow a pose source — keyframes, a pose file, a live UDP stream
//     (teleop/stream_message.hpp) or poses pushed with set_device_pose(). A
//     tool is kinematic (it is where its device puts it) or, with `coupling`,
//     a dynamic rigid body of the Newton solve pulled to the device by a
//     spring–damper (virtual coupling, energies/virtual_coupling.hpp). With a
//     shape it touches every body (SdfContactTerm); with sensors it grasps
//     (GraspController, AMBF Alg. 3) through one AnchorTerm per body;
//   * contact: one SdfContactTerm per colliding body–object pair (skin samples
//     every `sample_spacing`), one CapsuleContactTerm per colliding pair of
//     bodies (skipped when both are kinematic), and one per body with
//     self_contact; object–object and tool–object contact is not modelled.
#include <memory>
#include <string>
#include <vector>

#include "sflsh/scene/scene_description.hpp"
#include "sflsh/scene/simulation_run.hpp"
#include "sflsh/scene/tool_driver.hpp"
#include "sflsh/sim/simulator.hpp"
#include "sflsh/sim/step_report.hpp"
#include "sflsh/teleop/pose_sample.hpp"

namespace sflsh {

struct SceneSessionOptions {
  /// Print what building the scene does (mesh bakes, stream ports) to stderr.
  bool progress = true;
  /// Root push limit of bodies in body contact, as a fraction of body weight.
  double body_push_limit = 0.25;
  /// Open the UDP ports of tools with a `pose_stream` (false: such tools hold
  /// their keyframe pose unless poses are pushed with set_device_pose; for
  /// offline checks of a live scene).
  bool open_streams = true;
  /// Record the device poses each tool's steps used into DIR/<tool>.csv
  /// (teleop/pose_recorder.hpp; "" = no recording). finish_recording() puts
  /// the files in place.
  std::string record_dir;
  /// Replay a recording: every tool follows DIR/<tool>.csv with zero-order
  /// hold instead of its own pose source (its stream is not opened). Replaying
  /// a recorded session gives bit-identical trajectories.
  std::string replay_dir;
  /// TEST ONLY (`sflsh simulate --inject-nan-at-step N`): the first body's
  /// target of step N (1-based) gets a NaN pelvis bone translation, to drive
  /// the run into the numerical guard. 0 = off.
  long inject_nan_at_step = 0;
};

class SceneSession {
 public:
  /// Builds the scene (reads avatars, motions, materials, bakes meshes, opens
  /// stream ports). Throws sflsh::Error naming the scene file and the body,
  /// object or tool on inputs the runtime rejects.
  explicit SceneSession(const SceneDescription& scene, const SceneSessionOptions& options = {});
  /// One avatar driven by `motion` (run_simulation): a one-body scene of body
  /// "avatar" compiled by compile_avatar_motion with options.sim,
  /// options.skeleton and options.start_at_rest, lasting options.seconds (0:
  /// the motion's duration).
  SceneSession(std::shared_ptr<const Avatar> avatar, const MotionClip& motion, const RunOptions& options);
  ~SceneSession();
  SceneSession(const SceneSession&) = delete;
  SceneSession& operator=(const SceneSession&) = delete;

  const SceneDescription& scene() const;
  double dt() const;                ///< s, the solver's step
  double time() const;              ///< s simulated so far
  long steps_done() const;
  /// What messages call the run: the scene file, or the one avatar's motion.
  const std::string& name() const;
  /// Scene duration (s): solver.seconds, or the longest body motion.
  double seconds() const;
  /// Steps of the whole scene: max(1, round(seconds / dt)).
  long total_steps() const;

  /// Advances one step: reads the tools' pose sources, grasps/releases,
  /// steps the model, updates tool states and stream feedback. Throws naming
  /// the body/object/tool and the step when the state becomes non-finite.
  const StepReport& advance();
  /// Continues from `state` (a checkpoint of this scene's model, sim/state_file.hpp):
  /// steps_done() becomes its time in steps. Throws naming `where` when its
  /// time is not a whole number of steps or past the scene's end, or when the
  /// scene has tools (a State holds no grasp: resume from a file instead).
  void resume(const State& state, const std::string& where);
  /// Continues from the checkpoint file `path` (scene/scene_checkpoint.hpp):
  /// the state and what the tools hold; as resume(state) otherwise.
  void resume(const std::string& path);
  /// Writes the current state and the tools' grasps to `path` (atomically).
  void write_checkpoint(const std::string& path) const;
  const StepReport& last_report() const;

  /// Back to the scene's start (time 0, steps_done() 0): every body, dynamic
  /// object and coupled tool in its initial state; tools follow their
  /// keyframes / pose file again (pushed poses are dropped; a live stream's
  /// newest sample is taken at the next step, as at the start); grasps,
  /// events and the last report cleared; a recording (record_dir) starts over
  /// (the rows before the reset are dropped). The stiffness scales are
  /// settings and stay. Deterministic: reset() and N advance() calls give
  /// bit-identical states to a fresh session's N steps (with the same scales
  /// and pushed poses).
  void reset();
  /// Scales the soft-tissue stiffness of body `body` (−1: every body) by
  /// `scale` (> 0, 1 = the avatar's material) from the next step on: every
  /// region's Young's moduli and Fung c times `scale` (Poisson's ratio
  /// kept), which multiplies the elastic energy density — StVK, Fung
  /// saturation and the volume barrier — by exactly `scale`, and with it the
  /// stiffness-proportional damping (solver.damping). The state is kept.
  /// Throws naming the value or the body index when out of range.
  void set_stiffness_scale(double scale, int body = -1);
  /// The stiffness scale of body `body` (1 unless set).
  double stiffness_scale(int body) const;

  // Bodies (avatars), in the scene's order.
  int num_bodies() const;
  const std::string& body_name(int body) const;
  const Avatar& avatar(int body) const;
  /// #V by 3 posed skin (m, world) and soft displacement (m, unposed) of a body.
  Points body_surface(int body) const;
  Points body_displacement(int body) const;
  /// 24 by 3 joint positions (m, world).
  Points body_joints(int body) const;
  /// The body's target (motion) pose at time t, placed.
  BodyPose body_target_pose(int body, double t) const;
  /// The body's index in simulator().model().
  int body_model_index(int body) const;

  // Tools.
  int num_tools() const;
  const std::string& tool_name(int tool) const;
  /// Index of the tool named `name`; throws naming the known tools otherwise.
  int tool_index(const std::string& name) const;
  const SceneToolState& tool_state(int tool) const;
  /// The tool as compiled: its input ids and the model terms acting on it.
  const CompiledTool& compiled_tool(int tool) const;
  /// Pushes a device pose (world; closure rad) for the next steps: the tool
  /// follows pushed poses from now on (its keyframes/file are no longer read).
  /// Throws on a non-finite pose or a zero quaternion.
  void set_device_pose(int tool, const teleop::PoseSample& sample);
  /// The run is over: every live stream answers later poses with zero force
  /// and torque, status "ended" and the final sim_time (the device must not
  /// be left rendering the last force). advance() resumes the feedback.
  void end_feedback();
  /// The UDP port of a tool's pose stream (0 when it has none or streams are closed).
  int stream_port(int tool) const;
  /// Closes the recording (record_dir) and renames its files into place;
  /// returns their paths. Without it the recording leaves nothing behind.
  std::vector<std::string> finish_recording();
  /// Stream counters of a tool's live stream ("" when it has none).
  std::string stream_counters(int tool) const;
  /// Grasp and release events so far.
  const std::vector<SceneToolEvent>& tool_events() const;

  /// The result's constant part: every body's skin concatenated (surface,
  /// faces, body names and offsets), the objects' and tools' surfaces
  /// (objects first, then the tools with a shape), every tool's name
  /// (SimulationResult::tools) and every contact term's name and body
  /// (SimulationResult::contacts), no frames.
  SimulationResult result_header() const;
  /// Current poses of the result_header() objects, in its order (world).
  std::vector<Isometry> object_poses() const;
  /// The current state as an output frame (`step_ms`: the mean step time
  /// since the previous frame): every body's skin, displacement, joints and z,
  /// the first body's target pelvis (G_0 J̄_0 of its target bones), object
  /// poses, each tool's pose, closure, force and torque, each contact term's
  /// force, point, depth and active samples.
  FrameData frame(double step_ms) const;
  /// Every tool's current pose (as drawn), closure, force and torque, in
  /// result_header().tools order.
  std::vector<ToolFrame> tool_frames() const;
  /// Every contact term's force, point, depth and active samples from the last
  /// step (zero before the first), in result_header().contacts order.
  std::vector<ContactFrame> contact_frames() const;
  /// Appends the current state as a frame of `result` (made by result_header()):
  /// frame(step_ms) added with add_frame(); sets result.tool_events to the events so far.
  void record_frame(SimulationResult& result, double step_ms) const;

  /// The simulator: the same object for the session's life (references stay
  /// valid); set_stiffness_scale() gives it a new model (its terms rescaled).
  const Simulator& simulator() const;

 private:
  /// resume(state)'s part without the tools.
  void resume_at(const State& state, const std::string& where);
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace sflsh
