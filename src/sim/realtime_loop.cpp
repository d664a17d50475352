#include "sflsh/sim/realtime_loop.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "sflsh/core/error.hpp"

namespace sflsh {

RealtimeLoop::RealtimeLoop(const RealtimeOptions& options, Clock clock) : options_(options), clock_(std::move(clock)) {
  require(options_.substep > 0 && std::isfinite(options_.substep), "real-time loop: substep ", options_.substep,
          " s, expected > 0");
  require(options_.max_substeps >= 1, "real-time loop: max substeps ", options_.max_substeps, ", expected >= 1");
  if (!clock_)
    clock_ = [] {
      return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
    };
  start_ = clock_();
}

RealtimeFrame RealtimeLoop::frame(const std::function<void(double)>& substep) {
  RealtimeFrame f;
  f.wall_time = clock_() - start_;
  const double dt = options_.substep;
  const double lag = f.wall_time - sim_time() - dropped_;
  // ⌈lag/δt⌉, robust to the rounding of lag when it is a whole number of substeps.
  const double wanted = lag > 0 ? std::ceil(lag / dt - 1e-9) : 0.0;
  f.substeps = int(std::min<double>(wanted, options_.max_substeps));
  if (wanted > options_.max_substeps) {
    f.behind = true;
    f.dropped = lag - options_.max_substeps * dt;
    dropped_ += f.dropped;
    ++behind_;
  }
  for (int i = 0; i < f.substeps; ++i) {
    substep(sim_time());
    ++steps_;
  }
  f.sim_time = sim_time();
  f.rtf = rtf();
  return f;
}

double RealtimeLoop::rtf() const {
  const double wall = clock_() - start_;
  return wall > 0 ? sim_time() / wall : 0.0;
}

double RealtimeLoop::time_to_next() const { return sim_time() + dropped_ - (clock_() - start_); }

}  // namespace sflsh
