#pragma once
// Keeping a simulation in step with the wall clock (AMBF Eq. 1):
// a fixed substep δt and, per frame, N substeps,
//   N = min(⌈lag / δt⌉, N_max),   lag = wall time since start − simulated time − dropped,
// so that the simulated time follows the wall clock to within one substep when
// the machine keeps up (real-time factor RTF = simulated / wall time → 1).
// When it cannot (a substep costs more than δt of wall time), N is clamped at
// N_max and the lag beyond it is dropped instead of carried over: the
// simulation then runs slower than real time (RTF < 1, reported by `behind`)
// but every frame costs at most N_max substeps, so it never spirals.
// (AMBF's form counts the wall time since the previous frame; counting the lag
// from the start is the same when every frame runs its N, and keeps RTF at 1
// instead of drifting by the rounding of each ⌈·⌉.)
//
// The clock is injectable (seconds, monotonic) so tests can run it on a fake clock.
#include <functional>

namespace sflsh {

struct RealtimeOptions {
  double substep = 0.002;  ///< δt, s (> 0)
  int max_substeps = 10;   ///< N_max per frame (≥ 1)
};

/// What one frame did.
struct RealtimeFrame {
  int substeps = 0;         ///< N
  bool behind = false;      ///< N was clamped at N_max: lag was dropped
  double dropped = 0;       ///< s of wall time given up in this frame
  double sim_time = 0;      ///< s simulated since start, after the frame
  double wall_time = 0;     ///< s of wall clock since start, at the frame's start
  double rtf = 0;           ///< sim_time / wall time since start, after the frame (0 before any wall time)
};

class RealtimeLoop {
 public:
  using Clock = std::function<double()>;  ///< monotonic time in s
  /// Starts the clock now. Default clock: std::chrono::steady_clock.
  /// Throws on δt ≤ 0 or N_max < 1.
  explicit RealtimeLoop(const RealtimeOptions& options = {}, Clock clock = {});
  /// One frame: runs `substep(t)` N times (t = simulated time at the substep's
  /// start, s) with N from the header's formula. N = 0 when the simulation is
  /// ahead of the clock (the caller may wait; see time_to_next()).
  RealtimeFrame frame(const std::function<void(double)>& substep);
  /// Real-time factor so far: simulated / wall time since start (0 before any wall time).
  double rtf() const;
  double sim_time() const { return steps_ * options_.substep; }
  long long substeps() const { return steps_; }
  /// Frames clamped at N_max so far.
  long long frames_behind() const { return behind_; }
  /// Total wall time dropped (s).
  double dropped() const { return dropped_; }
  /// Wall time (s) until the next substep is due (≤ 0: due now).
  double time_to_next() const;
  const RealtimeOptions& options() const { return options_; }

 private:
  RealtimeOptions options_;
  Clock clock_;
  double start_ = 0;
  long long steps_ = 0, behind_ = 0;
  double dropped_ = 0;
};

}  // namespace sflsh
