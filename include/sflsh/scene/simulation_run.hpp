#pragma once
// Driving an avatar with a motion: the fixed-step loop around Simulator, frame
// output at its own rate, and the result file.
//
// The result file is in result_file.hpp.
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "sflsh/asset/avatar.hpp"
#include "sflsh/core/error.hpp"
#include "sflsh/motion/motion_clip.hpp"
#include "sflsh/sim/simulator.hpp"
#include "sflsh/sim/skeleton_terms.hpp"

namespace sflsh {

struct RunOptions {
  double seconds = 0;        ///< simulated time; 0 = the motion's duration
  double output_fps = 30;    ///< frames written per second of simulated time
  SimulatorOptions sim;      ///< h, bones dynamic/kinematic, Newton options, ...
  SkeletonTermsOptions skeleton;  ///< used when sim.bones_dynamic
  bool progress = true;      ///< show a progress line
  /// Called after every step (e.g. the benchmark records u); may be empty.
  std::function<void(const Simulator&, const StepReport&)> on_step;
  /// Keep every output frame in SimulationResult (memory: ~0.5 MB per frame
  /// for a 10k-vertex body). Long runs set false and stream with on_frame.
  bool keep_frames = true;
  /// Start at rest in the motion's first pose (true) or moving with the
  /// motion's velocity there (false: finite difference over the first step).
  bool start_at_rest = false;
  /// Continue from this checkpoint (sim/state_file.hpp) instead of the
  /// motion's first frame; the run then goes from the checkpoint's time to
  /// `seconds` (the end time). Frames start at the checkpoint's time.
  std::string resume;
  /// Save the final state here (a checkpoint to resume from).
  std::string checkpoint;
  /// TEST ONLY (`sflsh simulate --inject-nan-at-step N`, hidden): the motion
  /// target of step N (1-based) gets a NaN pelvis bone translation (with kinematic
  /// bones it becomes the state), to drive the run
  /// into the numerical guard. 0 = off.
  long inject_nan_at_step = 0;
};

/// A rigid object of a scene as results show it: its surface in
/// its own frame and its pose per output frame.
struct ObjectTrack {
  std::string name;
  std::string shape;            ///< "plane", "sphere", "box", "capsule", "cylinder", "mesh"
  std::string kind;             ///< "static", "kinematic", "dynamic"
  Points vertices;              ///< surface in the object's frame (m); a plane is a finite patch
  Triangles faces;
  std::vector<Isometry> poses;  ///< one per output frame: object frame → world
};

/// A tool of a scene at one output frame.
struct ToolFrame {
  Isometry pose = Isometry::Identity();  ///< tool frame → world (what is drawn)
  double closure = 0;                    ///< jaw opening of its device (rad, 0 = shut)
  /// Force (N) and torque (N·m, about the tool's frame origin) the bodies exert
  /// on the tool through its contact and anchors (world; SceneToolState).
  Vec3 force = Vec3::Zero(), torque = Vec3::Zero();
};

/// A tool of a scene as results show it: one ToolFrame per output frame.
struct ToolTrack {
  std::string name;
  std::vector<ToolFrame> frames;
};

/// A grasp or release by a tool (AMBF Alg. 3).
struct ToolEvent {
  double time = 0;               ///< s
  std::string tool, body, kind;  ///< kind: "grasp" | "release"
  int points = 0;                ///< skin points anchored or let go
};

/// A contact term of a scene at one output frame: its report at the end of
/// the step before the frame (zero before the first step and while the term
/// is inactive).
struct ContactFrame {
  Vec3 force = Vec3::Zero();  ///< N, world: what the term exerts on its body
  /// m, world: where it acts, the force-weighted mean of the term's active
  /// samples (capsule pairs: of their witness midpoints). Without one (no
  /// contact, or a term that reports none: the contact patch) the object's
  /// position for "contact:<object>", else the body's pelvis (joint 0).
  Vec3 point = Vec3::Zero();
  double max_penetration = 0;  ///< m: deepest sample (capsules: largest overlap)
  int active = 0;              ///< samples (capsule pairs) in contact
};

/// A contact term of a scene as results show it: body–object
/// ("contact:<object>", tools' shapes and jaws too), body–body
/// ("skin_contact", "body_contact") or "self_contact"; one ContactFrame per
/// output frame. Tools' anchors are not contacts (their force is ToolFrame::force).
struct ContactTrack {
  std::string term;  ///< the term's name
  std::string body;  ///< the body it acts on (its first body; the other one feels the opposite force)
  std::vector<ContactFrame> frames;
};

/// One output frame (what the result file stores per frame).
struct FrameData {
  double time = 0, step_ms = 0;
  /// Skin of every body, concatenated in body order (SimulationResult::body_vertex_offsets).
  Points positions, displacement;
  Points joints;  ///< 24 rows per body, in body order
  VecX reduced;   ///< every body's z, concatenated
  Vec3 target_pelvis = Vec3::Zero();  ///< the motion's pelvis at `time` (world, m; first body)
  std::vector<Isometry> object_poses;  ///< one per SimulationResult::objects entry
  std::vector<ToolFrame> tools;        ///< one per SimulationResult::tools entry
  std::vector<ContactFrame> contacts;  ///< one per SimulationResult::contacts entry
};

struct SimulationResult {
  std::string avatar, motion;
  /// Scenes with several bodies: their names, and where each one's skin
  /// vertices start in faces/positions (#bodies + 1 entries). Empty = one body.
  std::vector<std::string> body_names;
  std::vector<int> body_vertex_offsets;
  /// Rigid objects of the scene (poses per output frame); empty without objects.
  std::vector<ObjectTrack> objects;
  /// Tools of the scene (a frame per output frame) and their grasp and release
  /// events; empty without tools.
  std::vector<ToolTrack> tools;
  std::vector<ToolEvent> tool_events;
  /// Contact terms of the scene (a frame per output frame); empty without
  /// contacts and when read from a file written before they were stored.
  std::vector<ContactTrack> contacts;
  double dt = 0;
  bool bones_dynamic = false;
  int newton_iters = 1;
  Triangles faces;
  Points surface_rest;
  std::vector<double> frame_time, frame_step_ms;
  std::vector<Points> frame_positions, frame_displacement, frame_joints;
  std::vector<VecX> frame_reduced;
  std::vector<Vec3> frame_target_pelvis;  ///< empty when read from a file without it
  std::vector<double> step_time, step_energy, step_grad_norm, step_decrement, step_ms;
  std::vector<int> step_outcome;
  /// Every body's 24 bones (body b's at 24 b .. 24 b + 23) at the end of each
  /// step, and at the run's start: start_bones[0] at t − h, [1] at t. What
  /// `sflsh fit` prescribes to reproduce a run whose bones were dynamic. Empty
  /// when not recorded (read from a file without them, a live run).
  std::vector<std::vector<Isometry>> step_bones, start_bones;
  int num_frames = 0;  ///< output frames made (kept or not)
  /// Distance between the simulated pelvis (joint 0) and the motion's pelvis
  /// over the output frames (kept or not), m; pelvis_frames = 0 when unknown.
  double pelvis_error_mean = 0, pelvis_error_max = 0;
  int pelvis_frames = 0;
  int accepted = 0, damped = 0, rejected = 0;
  /// Where the step time goes: each energy term's evaluations and the
  /// Cholesky solve, summed over all steps (ms), in the step's term order.
  std::vector<std::string> part_names;
  std::vector<double> part_ms;
  /// The run stopped early (the numerical guard, sim/finite_guard.hpp): the
  /// frames and steps are those before the stop; `stop_reason` says why.
  bool incomplete = false;
  std::string stop_reason;

  /// Adds a step's per-term and solve times to part_names/part_ms.
  void add_step_times(const StepReport& report);
  /// Records a step ending at time t (s): the step_* series, its times and outcome counts.
  void add_step(double t, const StepReport& report);
  /// Keeps an output frame: the frame_* series, each object's pose, each
  /// tool's and each contact's frame (num_frames and the pelvis figures are
  /// counted apart).
  void add_frame(FrameData frame);
  /// Median / 95th percentile step wall time (ms).
  double median_step_ms() const;
  double p95_step_ms() const;
  std::string describe() const;
};

/// Thrown by the run loop (run_scene, run_simulation) when the numerical guard trips: what() names the
/// step, the term and the body; `partial` holds what was made before the
/// step (frames already passed to on_frame, steps), marked incomplete.
class SimulationStopped : public Error {
 public:
  SimulationStopped(const std::string& what, SimulationResult partial) : Error(what), partial(std::move(partial)) {}
  SimulationResult partial;
};

/// Simulates `avatar` following `motion` from its first frame (state reset to
/// the motion's first pose, moving with the motion unless
/// RunOptions::start_at_rest; soft tissue undeformed). Every output frame is passed to
/// `on_frame` (if given) as it is made. Throws SimulationStopped if the state
/// or an energy becomes non-finite (no frame of that step is made).
/// The avatar and motion are a one-body scene (SceneSession's one-avatar
/// constructor) run by the scene files' loop, run_scene (scene_run.hpp).
SimulationResult run_simulation(std::shared_ptr<const Avatar> avatar, const MotionClip& motion, const RunOptions& options,
                                const std::function<void(const FrameData&)>& on_frame = {});

/// Steps run_simulation takes (without a resume): max(1, round(seconds / h)),
/// seconds = options.seconds if > 0, else the motion's duration (s). A clip
/// whose duration is not a whole number of steps gets its last step past its
/// end when the remainder is ≥ h/2 (the motion holds its last frame there).
long run_step_count(const MotionClip& motion, const RunOptions& options);

/// Bone transforms (24 world) of a motion pose on the avatar's skeleton.
std::vector<Isometry> target_bones(const Avatar& avatar, const BodyPose& pose);

}  // namespace sflsh
