#pragma once
// Running a scene session live (`sflsh run scene.yaml`): in step
// with the wall clock (--realtime: RealtimeLoop, AMBF Eq. 1: N substeps of the
// solver's dt per frame, N ≤ max_substeps, the lag beyond dropped so a slow
// machine runs behind real time but never spirals), or as fast as it can
// (deterministic: the same steps whatever the machine). Either way it reports
// the real-time factor (RTF = simulated / wall time) as it goes and at the end,
// calls hooks once per frame (the display rate) — where a viewer publishes
// frames and pushes device poses — and stops at the scene's end, at
// `seconds`, or on SIGINT/SIGTERM (a normal end for a live session).
#include <functional>
#include <string>
#include <vector>

#include "sflsh/scene/scene_session.hpp"
#include "sflsh/scene/simulation_run.hpp"

namespace sflsh {

struct LiveRunOptions {
  bool realtime = false;
  double seconds = 0;        ///< s of simulation; 0 = the scene's (SceneSession::seconds)
  int max_substeps = 10;     ///< N_max per frame (real time)
  /// As fast as possible: frames (hooks) per simulated second (Hz). Real
  /// time: a frame starts whenever a substep is due (the newest device pose
  /// goes into every step), with several substeps only when catching up.
  double frame_rate = 60;
  /// A status line (simulated time, RTF, substeps per frame, step time,
  /// tool forces) to stderr about once per wall second.
  bool progress = true;
};

/// Per-frame hooks; each may be empty.
struct LiveRunHooks {
  /// Before each frame's substeps (e.g. push the latest device poses).
  /// Return false to stop the run.
  std::function<bool(SceneSession&)> before_frame;
  /// After each frame (e.g. publish the skin to a viewer).
  std::function<void(const SceneSession&, const struct LiveRunStatus&)> after_frame;
  /// After each step (e.g. record a result frame or a tool log row).
  std::function<void(const SceneSession&, const StepReport&)> after_step;
};

/// Where a live run stands.
struct LiveRunStatus {
  long steps = 0;
  long damped = 0, rejected = 0;  ///< steps whose worst Newton iteration was damped / rejected
  long frames = 0;
  long frames_behind = 0;       ///< real time: frames clamped at max_substeps
  double sim_time = 0;          ///< s simulated in this run
  double wall_time = 0;         ///< s of wall clock since the run started
  double dropped = 0;           ///< s of wall time not caught up (real time)
  double rtf = 0;               ///< sim_time / wall_time
  double last_substeps = 0;     ///< substeps in the last frame
  bool interrupted = false;     ///< ended by SIGINT/SIGTERM
  std::vector<double> step_ms;  ///< every step's wall time (ms)
  /// The end-of-run summary: time, RTF, frames behind, step time median/p99.
  std::string describe(bool realtime) const;
};

/// Runs `session` to its end (or options.seconds, or a signal). Throws what
/// SceneSession::advance throws (a non-finite state).
LiveRunStatus run_live(SceneSession& session, const LiveRunOptions& options, const LiveRunHooks& hooks = {});

}  // namespace sflsh
