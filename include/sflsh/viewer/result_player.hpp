#pragma once
// Playing a result file in the viewer (`sflsh view result.h5`): a playback
// clock driven by the page's controls (play/pause, seek, speed, step, reset)
// and the frame shown at each time.
#include <vector>

#include "sflsh/scene/simulation_run.hpp"
#include "sflsh/viewer/control_message.hpp"
#include "sflsh/viewer/frame_codec.hpp"

namespace sflsh::viewer {

/// The result frame shown at time t (s): the last frame whose time is <= t
/// (to within 1e-9 s); frame 0 before the first. `frame_time` ascending, not empty.
int frame_at(const std::vector<double>& frame_time, double t);

/// Result frame `f` as a viewer frame: positions, |u| per vertex, joints, object poses,
/// every tool's pose, closure, force and torque, every contact's force, point, depth and samples.
ViewerFrame result_frame(const SimulationResult& result, int f);

class ResultPlayer {
 public:
  /// Starts paused at the first frame at speed 1. `result` must outlive the player.
  explicit ResultPlayer(const SimulationResult& result);

  /// Applies a control: pause (play/pause; playing from the end restarts at
  /// the start), seek (clamped to [first, last] frame time), speed, step (one
  /// frame forward, paused), reset (first frame, paused). Tool and stiffness
  /// messages do not apply to playback: returns false for them.
  bool apply(const ControlMessage& message);
  /// Advances the clock by `wall_seconds` × speed when playing; pauses at the last frame.
  void advance(double wall_seconds);

  double time() const { return time_; }
  int frame() const { return frame_at(result_.frame_time, time_); }
  bool paused() const { return paused_; }
  double speed() const { return speed_; }
  /// The frame shown now (result_frame of frame()), with the playback's stats.
  ViewerFrame current() const;

 private:
  const SimulationResult& result_;
  double time_ = 0, speed_ = 1;
  bool paused_ = true;
};

}  // namespace sflsh::viewer
