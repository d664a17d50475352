#include "sflsh/scene/live_run.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <sstream>
#include <thread>

#include "sflsh/core/error.hpp"
#include "sflsh/core/interrupt.hpp"
#include "sflsh/core/percentile.hpp"
#include "sflsh/sim/realtime_loop.hpp"

namespace sflsh {
namespace {

double wall_seconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

/// "t = 3.00 s  RTF 1.00  8.3 substeps/frame  step 1.21 ms  probe 3.2 N 4 anchors"
void print_status(const SceneSession& s, const LiveRunStatus& st, bool realtime, size_t steps_before) {
  double ms = 0;
  for (size_t i = steps_before; i < st.step_ms.size(); ++i) ms += st.step_ms[i];
  const size_t n = st.step_ms.size() - steps_before;
  std::ostringstream o;
  char buf[160];
  std::snprintf(buf, sizeof buf, "t = %.2f s  RTF %.2f", s.time(), st.rtf);
  o << buf;
  if (realtime) {
    std::snprintf(buf, sizeof buf, "  %.1f substeps/frame  %ld frames behind", st.last_substeps, st.frames_behind);
    o << buf;
  }
  std::snprintf(buf, sizeof buf, "  step %.2f ms", n ? ms / double(n) : 0.0);
  o << buf;
  for (int i = 0; i < s.num_tools(); ++i) {
    const SceneToolState& t = s.tool_state(i);
    std::snprintf(buf, sizeof buf, "  %s %.1f N", s.tool_name(i).c_str(), t.feedback_force.norm());
    o << buf;
    if (t.anchors) o << " " << t.anchors << " anchors";
  }
  std::cerr << o.str() << "\n";
}

}  // namespace

std::string LiveRunStatus::describe(bool realtime) const {
  std::ostringstream o;
  char buf[256];
  std::snprintf(buf, sizeof buf, "%s: simulated %.3f s in %.3f s of wall time (%ld steps), RTF %.3f",
                realtime ? "real time" : "as fast as possible", sim_time, wall_time, steps, rtf);
  o << buf;
  if (realtime) {
    std::snprintf(buf, sizeof buf, "; %ld frames, %ld behind (clamped at max substeps, %.3f s dropped)%s", frames,
                  frames_behind, dropped, frames_behind > 0 ? " — the machine could not keep up" : "");
    o << buf;
  }
  if (!step_ms.empty()) {
    std::snprintf(buf, sizeof buf, "\nsteps: %ld accepted, %ld damped, %ld rejected; step time median %.3f ms, p99 %.3f ms, max %.3f ms",
                  steps - damped - rejected, damped, rejected, percentile(step_ms, 0.5), percentile(step_ms, 0.99),
                  percentile(step_ms, 1.0));
    o << buf;
  }
  if (interrupted) o << "\nended by a signal";
  return o.str();
}

LiveRunStatus run_live(SceneSession& s, const LiveRunOptions& opt, const LiveRunHooks& hooks) {
  require(opt.seconds >= 0 && std::isfinite(opt.seconds), "run: seconds ", opt.seconds, ", expected >= 0");
  require(opt.frame_rate > 0 && std::isfinite(opt.frame_rate), "run: frame rate ", opt.frame_rate, " Hz, expected > 0");
  const long end_step =
      s.steps_done() + (opt.seconds > 0 ? std::max(1L, long(std::llround(opt.seconds / s.dt()))) : s.total_steps());
  LiveRunStatus st;
  const double start = wall_seconds();
  double next_status = start + 1.0;
  size_t status_from = 0;
  auto one_step = [&] {
    const double t0 = wall_seconds();
    const StepReport& rep = s.advance();
    st.step_ms.push_back((wall_seconds() - t0) * 1e3);
    ++st.steps;
    if (rep.outcome == StepOutcome::Damped) ++st.damped;
    if (rep.outcome == StepOutcome::Rejected) ++st.rejected;
    if (hooks.after_step) hooks.after_step(s, rep);
  };
  auto end_frame = [&] {
    ++st.frames;
    st.wall_time = wall_seconds() - start;
    st.sim_time = double(st.steps) * s.dt();  // not s.time(): SceneSession::reset() sends it back to 0
    st.rtf = st.wall_time > 0 ? st.sim_time / st.wall_time : 0.0;
    if (hooks.after_frame) hooks.after_frame(s, st);
    if (opt.progress && wall_seconds() >= next_status) {
      print_status(s, st, opt.realtime, status_from);
      status_from = st.step_ms.size();
      next_status += 1.0;
    }
  };
  const bool done_at_start = s.steps_done() >= end_step;
  if (opt.realtime) {
    RealtimeOptions ro;
    ro.substep = s.dt();
    ro.max_substeps = opt.max_substeps;
    RealtimeLoop loop(ro);
    while (!done_at_start && s.steps_done() < end_step) {
      if (interrupt_signal()) {
        st.interrupted = true;
        break;
      }
      if (hooks.before_frame && !hooks.before_frame(s)) break;
      const RealtimeFrame f = loop.frame([&](double) {
        if (s.steps_done() < end_step) one_step();
      });
      st.last_substeps = f.substeps;
      st.frames_behind = loop.frames_behind();
      st.dropped = loop.dropped();
      end_frame();
      // Sleep until the next substep is due: a frame runs as soon as the wall
      // clock has a substep's lag (the device's newest pose goes into every
      // step), more substeps at once only when catching up.
      const double wait = loop.time_to_next();
      if (wait > 0) std::this_thread::sleep_for(std::chrono::duration<double>(wait));
    }
  } else {
    const long steps_per_frame = std::max(1L, long(std::llround(1.0 / (opt.frame_rate * s.dt()))));
    while (!done_at_start && s.steps_done() < end_step) {
      if (interrupt_signal()) {
        st.interrupted = true;
        break;
      }
      if (hooks.before_frame && !hooks.before_frame(s)) break;
      for (long i = 0; i < steps_per_frame && s.steps_done() < end_step; ++i) one_step();
      st.last_substeps = double(steps_per_frame);
      end_frame();
    }
  }
  s.end_feedback();
  st.wall_time = wall_seconds() - start;
  st.sim_time = double(st.steps) * s.dt();
  st.rtf = st.wall_time > 0 ? st.sim_time / st.wall_time : 0.0;
  return st;
}

}  // namespace sflsh
