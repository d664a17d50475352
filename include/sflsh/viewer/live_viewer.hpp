#pragma once
// `sflsh run scene.yaml --serve`: a SceneSession shown and driven in the
// browser. The page's tool poses become the first tool's device poses
// (SceneSession::set_device_pose, the same interface as the device stream);
// pause, step, reset (SceneSession::reset) and the stiffness slider
// (SceneSession::set_stiffness_scale, every body) come from the page and are
// applied between frames; frames go out at the display rate from run_live's
// per-frame hook, never blocking the physics.
#include <memory>
#include <string>

#include "sflsh/scene/live_run.hpp"
#include "sflsh/scene/scene_session.hpp"
#include "sflsh/viewer/viewer_server.hpp"

namespace sflsh::viewer {

class LiveViewer {
 public:
  /// Builds the viewer scene from `session` (its skin, objects, tools) and
  /// starts the server (prints the URL on stdout). `session` must outlive it.
  /// `allow_reset` false: reset messages are logged and ignored and the page
  /// disables its button (a run writing files along the time line).
  LiveViewer(SceneSession& session, const ViewerServerOptions& options, const std::string& title,
             bool allow_reset = true);
  ~LiveViewer();

  /// Sets hooks.before_frame (apply the page's controls; hold while paused),
  /// wraps hooks.after_step (the run's own hook first; then the controls and,
  /// when one is due, a frame: between substeps, so a real-time frame that
  /// runs max_substeps delays neither) and sets hooks.after_frame (a frame
  /// when due). Install after setting the run's own after_step.
  void install(LiveRunHooks& hooks);
  /// The frame of the session's current state (public for tests).
  ViewerFrame frame(const LiveRunStatus& status) const;
  /// One line: frames served, clients, bandwidth, controls applied/ignored,
  /// the largest |u| seen (mm), the frames with tool contact and the mean
  /// time building a frame on the physics thread (ms).
  std::string summary() const;
  ViewerServer& server();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace sflsh::viewer
