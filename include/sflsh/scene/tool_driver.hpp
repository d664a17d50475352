#pragma once
// Driving one tool of a compiled scene (scene_compiler.hpp) step by step: its
// pose source — keyframes or a pose file (interpolated linearly, or held for a
// recording), a live UDP stream (teleop/pose_stream_link.hpp) or poses pushed
// by a program or the viewer — with the live device's ramped take-over; the
// world frames the step reads (the tool or its device for a coupled tool, its
// jaws, its anchors); grasping and releasing per body (GraspController, AMBF
// Alg. 3); after the step the force and torque the bodies exert on it and the
// feedback sent to the device; and the recording of the device poses used.
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "sflsh/scene/scene_compiler.hpp"
#include "sflsh/scene/simulation_run.hpp"
#include "sflsh/sim/simulator.hpp"
#include "sflsh/sim/step_report.hpp"
#include "sflsh/teleop/pose_ramp.hpp"
#include "sflsh/teleop/pose_sample.hpp"

namespace sflsh {

namespace teleop {
class PoseStreamLink;
class PoseRecorder;
class PoseTrack;
}  // namespace teleop

/// A tool after the latest step.
struct SceneToolState {
  /// The device (pose source) sample the last step drove the tool to.
  teleop::PoseSample device;
  /// The tool's pose at the current time (world): the device's for a
  /// kinematic tool, the coupled rigid body's with a coupling.
  Isometry pose = Isometry::Identity();
  /// Force (N) and torque (N·m, about the tool's frame origin) the bodies
  /// exert on the tool through its contact and anchors (world).
  Vec3 force = Vec3::Zero(), torque = Vec3::Zero();
  /// What the device is sent: the coupling's force and torque on the device
  /// (kinematic tool: force/torque above), times haptic_gain, the force
  /// clamped to max_force (N, N·m, world).
  Vec3 feedback_force = Vec3::Zero(), feedback_torque = Vec3::Zero();
  int anchors = 0;           ///< flesh points anchored now
  double max_stretch = 0;    ///< m, the largest anchor stretch |x_p − a_p|
  bool live = false;         ///< the pose comes from a stream or set_device_pose()
  bool ramping_in = false;   ///< the tool is still being brought to the device (pose_stream.ramp_in)
};

/// A grasp or release (AMBF Alg. 3; simulation_run.hpp).
using SceneToolEvent = ToolEvent;

struct ToolDriverOptions {
  /// Print the stream's port to stderr when it opens.
  bool progress = true;
  /// Open the UDP port of a tool with a `pose_stream` (false: it holds its
  /// keyframe pose unless poses are pushed).
  bool open_stream = true;
  /// Record the device poses the steps used into DIR/<tool>.csv ("" = no recording).
  std::string record_dir;
  /// Follow DIR/<tool>.csv with zero-order hold instead of the tool's own
  /// pose source (its stream is not opened).
  std::string replay_dir;
  /// The scene file, for messages.
  std::string scene_path;
};

class ToolDriver {
 public:
  /// Reads the tool's pose source and opens its stream. `tool` (and the scene
  /// it was compiled from) must outlive the driver. Throws naming the scene
  /// file and the tool when the pose file cannot be read or the port opened.
  ToolDriver(const CompiledTool& tool, int num_bodies, const ToolDriverOptions& options);
  ~ToolDriver();
  ToolDriver(ToolDriver&&) noexcept;
  ToolDriver& operator=(ToolDriver&&) noexcept;

  const CompiledTool& tool() const { return *tool_; }
  const std::string& name() const { return tool_->desc->name; }

  /// Puts the tool at its device pose at t = 0 (a coupled tool's body in `s`,
  /// at rest) and starts its recording.
  void start(State& s);
  /// Back to before start(): pushed and streamed poses dropped, grasps
  /// released, state cleared, the recording's rows so far dropped.
  void reset();
  /// Continues at time t (after reset()) from a checkpoint: the simulator
  /// holds its state (a coupled tool's body in it), `grasps` what the tool
  /// held per body. The pose source is read from t on (a live stream takes
  /// over again, ramped, as at the start); a recording starts at t.
  void resume(const Simulator& sim, double t, std::vector<std::vector<Anchor>> grasps);
  /// The anchors held per body now (empty per body without a grasp; none
  /// for a tool without sensors).
  std::vector<std::vector<Anchor>> grasped() const;
  /// The device pose of the next steps (world, closure rad; normalized): the
  /// tool follows pushed poses from now on. Throws on a non-finite pose or a
  /// zero quaternion.
  void push(const teleop::PoseSample& sample);

  /// The inputs of the step from t − h to t: reads the stream, takes over a
  /// newly live tool, writes the tool's (or its device's), jaws' and anchors'
  /// world frames into `in`, grasps or releases per body (events appended to
  /// `events`) and records the device pose used.
  void drive(Simulator& sim, const std::vector<CompiledBody>& bodies, double t, double h, StepInputs& in,
             std::vector<SceneToolEvent>& events);
  /// After the step that ended at t: the force and torque on the tool, its
  /// anchors, its pose and the feedback, published to the stream.
  void feel(const Simulator& sim, const StepReport& report, double t);
  /// The stream answers later poses with zero force and status "ended".
  void end_feedback();

  const SceneToolState& state() const { return state_; }
  /// The pose to draw at time t: the track's (linearly interpolated) pose for
  /// a kinematic tool on keyframes or a pose file, else state().pose.
  Isometry drawn_pose(double t) const;
  /// A jaw's world pose now (the tool's pose, the device's closure).
  Isometry jaw_pose(const CompiledJaw& jaw) const;

  /// The stream's UDP port (0 without a stream).
  int stream_port() const;
  /// The stream's counters ("" without a stream).
  std::string stream_counters() const;
  /// Closes the recording and renames its file into place; returns its path
  /// ("" when not recording).
  std::string finish_recording();

 private:
  /// The tool's body pose at the current time (coupled) or its device's.
  Isometry pose(const Simulator& sim) const;
  /// The live device takes over at t0: from the tool's pose by a ramp when it
  /// has keyframes or a pose file, else the tool is placed on the device's
  /// first pose (a coupled body with it, at rest).
  void take_over(Simulator& sim, double t0);
  /// Opens the recording (options_.record_dir) with the device sample at t.
  void start_recording(double t);

  const CompiledTool* tool_;
  ToolDriverOptions options_;
  int num_bodies_ = 0;
  std::unique_ptr<teleop::PoseTrack> track_;  ///< keyframes, pose file or recording
  bool hold_ = false;                         ///< the track is a recording: zero-order hold
  std::unique_ptr<teleop::PoseStreamLink> link_;
  std::uint64_t link_sequence_ = 0;  ///< the newest stream sample taken
  bool link_seen_ = false;
  bool live_ = false;                ///< the pose comes from the stream or push()
  teleop::PoseSample pushed_;        ///< the live device's newest sample
  teleop::PoseSample device_now_;    ///< the device sample at the current time
  teleop::PoseRamp ramp_;            ///< the live device's take-over
  std::vector<GraspController> grasps_;  ///< per body (tools with sensors)
  std::unique_ptr<teleop::PoseRecorder> recorder_;
  teleop::PoseSample recorded_;      ///< the last sample recorded
  SceneToolState state_;
};

}  // namespace sflsh
