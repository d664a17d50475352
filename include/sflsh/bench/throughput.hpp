#pragma once
// `sflsh bench-throughput` ("Throughput for many avatars"): a batch
// of independent avatars, each driven by the same motion at its own phase,
// stepped together with sim/batch_step.hpp on 1, 2, ... threads. Reports
// avatar-steps per second per (avatars, threads) and the speed-up over one
// thread for the same batch. The avatars share one Model (dynamic bones with
// the skeleton terms, one Newton step per time step: `sflsh simulate`'s
// defaults); each has its own State.
#include <memory>
#include <string>
#include <vector>

#include "sflsh/asset/avatar.hpp"

namespace sflsh {

struct ThroughputOptions {
  std::string motion = "builtin:jump";
  double dt = 1.0 / 60.0;
  std::vector<int> avatars = {1, 4, 16};   ///< batch sizes
  std::vector<int> threads = {1, 2};       ///< thread counts (each >= 1)
  long steps = 120;                        ///< timed steps per batch and thread count
  long warmup_steps = 5;                   ///< untimed steps first (caches, page faults)
  /// Avatar i starts `phase` · i seconds into the motion (wrapped), so the
  /// batch's states differ.
  double phase = 0.37;
};

struct ThroughputRow {
  int avatars = 0, threads = 0;
  long steps = 0;               ///< timed steps (each steps every avatar)
  double seconds = 0;           ///< wall time of the timed steps
  double avatar_steps_per_s = 0;
  double ms_per_batch_step = 0; ///< wall ms per step of the whole batch
  double speedup = 0;           ///< avatar_steps_per_s / the 1-thread row's (same batch size); 0 if none
  int damped = 0, rejected = 0; ///< over the timed steps, every avatar
};

struct ThroughputReport {
  std::vector<ThroughputRow> rows;
  int hardware_threads = 0;     ///< std::thread::hardware_concurrency()
  double load_before = -1, load_after = -1;  ///< 1-min load average (/proc/loadavg), -1 if unknown
  std::string describe() const;  ///< the markdown table
};

/// Runs every (avatars, threads) combination (progress on stderr).
ThroughputReport run_throughput(std::shared_ptr<const Avatar> avatar, const ThroughputOptions& options);

/// CSV: avatars,threads,steps,seconds,avatar_steps_per_s,ms_per_batch_step,speedup,damped,rejected.
void write_throughput_csv(const ThroughputReport& report, const std::string& path);
/// Markdown: the command's settings, machine load and the table.
void write_throughput_markdown(const ThroughputReport& report, const ThroughputOptions& options,
                               const std::string& avatar_name, const std::string& path);

}  // namespace sflsh
