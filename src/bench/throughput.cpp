#include "sflsh/bench/throughput.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <sstream>
#include <thread>

#include "sflsh/core/error.hpp"
#include "sflsh/io/atomic_output.hpp"
#include "sflsh/motion/load_motion.hpp"
#include "sflsh/scene/simulation_run.hpp"
#include "sflsh/sim/batch_step.hpp"

namespace sflsh {
namespace {

double load_average() {
  std::ifstream f("/proc/loadavg");
  double l = -1;
  if (!(f >> l)) return -1;
  return l;
}

/// Targets of every avatar for steps 0..steps (inclusive; step s at time s·h + offset).
struct Drive {
  std::vector<std::vector<StepInputs>> inputs;  // [avatar][step]
};

Drive make_drive(const Avatar& avatar, const MotionClip& motion, int avatars, long steps, double h, double phase) {
  Drive d;
  const double T = motion.duration();
  d.inputs.resize(avatars);
  for (int a = 0; a < avatars; ++a) {
    const double offset = T > 0 ? std::fmod(phase * a, T) : 0.0;
    d.inputs[a].resize(steps + 1);
    for (long s = 0; s <= steps; ++s) {
      double t = offset + s * h;
      if (T > 0) t = std::fmod(t, T);
      const BodyPose pose = motion.sample(t);
      d.inputs[a][s].bodies.push_back({target_bones(avatar, pose), pose});
    }
  }
  return d;
}

void write_text(const std::string& path, const std::string& text) {
  io::write_text_file(path, [&](std::ostream& f) {
    f << text;
  });
}

std::string table(const ThroughputReport& r) {
  std::ostringstream o;
  o << "| avatars | threads | steps | wall s | avatar-steps/s | ms per batch step | speed-up vs 1 thread | damped | rejected |\n"
    << "|---|---|---|---|---|---|---|---|---|\n";
  for (const ThroughputRow& w : r.rows) {
    o << "| " << w.avatars << " | " << w.threads << " | " << w.steps << " | " << std::fixed << std::setprecision(3)
      << w.seconds << " | " << std::setprecision(0) << w.avatar_steps_per_s << " | " << std::setprecision(3)
      << w.ms_per_batch_step << " | " << std::setprecision(2) << w.speedup << " | " << w.damped << " | " << w.rejected
      << " |\n";
  }
  return o.str();
}

}  // namespace

std::string ThroughputReport::describe() const {
  std::ostringstream o;
  o << table(*this) << std::fixed << std::setprecision(2) << "load average (1 min) before " << load_before
    << ", after " << load_after << "; " << hardware_threads << " hardware threads\n";
  return o.str();
}

ThroughputReport run_throughput(std::shared_ptr<const Avatar> avatar, const ThroughputOptions& o) {
  require(avatar != nullptr, "bench-throughput: null avatar");
  require(o.steps >= 1, "bench-throughput: --steps must be >= 1, got ", o.steps);
  require(o.warmup_steps >= 0, "bench-throughput: warm-up steps must be >= 0, got ", o.warmup_steps);
  require(o.dt > 0 && std::isfinite(o.dt), "bench-throughput: --dt must be positive, got ", o.dt);
  require(!o.avatars.empty() && !o.threads.empty(), "bench-throughput: --avatars and --threads need at least one value");
  for (int a : o.avatars) require(a >= 1 && a <= 4096, "bench-throughput: --avatars entry ", a, ", expected in [1, 4096]");
  for (int t : o.threads) require(t >= 1 && t <= 1024, "bench-throughput: --threads entry ", t, ", expected in [1, 1024]");

  const long total = o.warmup_steps + o.steps;
  MotionOptions mo;
  mo.rest_joints = avatar->joints_rest;
  mo.builtin_seconds = std::max(5.0, double(total + 1) * o.dt);
  const MotionClip motion = load_motion(o.motion, mo);

  RunOptions ro;  // `sflsh simulate`'s defaults: dynamic bones, skeleton terms, one Newton step
  ro.sim.h = o.dt;
  ro.sim.bones_dynamic = true;
  const std::shared_ptr<const Model> model = avatar_model(avatar, ro.sim, &ro.skeleton);

  ThroughputReport rep;
  rep.hardware_threads = int(std::thread::hardware_concurrency());
  rep.load_before = load_average();
  int largest = 0;
  for (int a : o.avatars) largest = std::max(largest, a);
  const Drive drive = make_drive(*avatar, motion, largest, total, o.dt, o.phase);

  for (int A : o.avatars) {
    double one_thread = 0;
    for (int T : o.threads) {
      std::fprintf(stderr, "  bench-throughput: %d avatars on %d thread(s)...\n", A, T);
      std::vector<const Model*> models(A, model.get());
      std::vector<State> states;
      for (int a = 0; a < A; ++a) {
        State s = rest_state(*model);
        s.bodies[0].q.bones = drive.inputs[a][0].bodies[0].bones;
        s.bodies[0].q_prev.bones = s.bodies[0].q.bones;
        states.push_back(std::move(s));
      }
      std::vector<StepInputs> in(A);
      std::vector<StepReport> reports;
      ThroughputRow row;
      row.avatars = A;
      row.threads = T;
      row.steps = o.steps;
      std::chrono::steady_clock::time_point start;
      for (long s = 1; s <= total; ++s) {
        if (s == o.warmup_steps + 1) start = std::chrono::steady_clock::now();
        for (int a = 0; a < A; ++a) in[a] = drive.inputs[a][s];
        step_batch(models, states, in, T, &reports);
        if (s > o.warmup_steps)
          for (const StepReport& r : reports) row.damped += r.damped, row.rejected += r.rejected;
      }
      row.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      row.avatar_steps_per_s = double(A) * double(o.steps) / row.seconds;
      row.ms_per_batch_step = 1e3 * row.seconds / double(o.steps);
      if (T == 1) one_thread = row.avatar_steps_per_s;
      row.speedup = one_thread > 0 ? row.avatar_steps_per_s / one_thread : 0.0;
      rep.rows.push_back(row);
    }
  }
  rep.load_after = load_average();
  return rep;
}

void write_throughput_csv(const ThroughputReport& r, const std::string& path) {
  std::ostringstream o;
  o << "avatars,threads,steps,seconds,avatar_steps_per_s,ms_per_batch_step,speedup,damped,rejected\n";
  o << std::setprecision(6);
  for (const ThroughputRow& w : r.rows)
    o << w.avatars << ',' << w.threads << ',' << w.steps << ',' << w.seconds << ',' << w.avatar_steps_per_s << ','
      << w.ms_per_batch_step << ',' << w.speedup << ',' << w.damped << ',' << w.rejected << '\n';
  write_text(path, o.str());
}

void write_throughput_markdown(const ThroughputReport& r, const ThroughputOptions& o, const std::string& avatar_name,
                               const std::string& path) {
  std::ostringstream m;
  m << "# `sflsh bench-throughput`\n\n"
    << "Avatar " << avatar_name << ", motion " << o.motion << " (avatar i starts " << o.phase
    << " s · i into it), dt " << o.dt << " s, dynamic bones, one Newton step; " << o.steps << " timed steps after "
    << o.warmup_steps << " warm-up steps per row. The avatars share one Model, each has its own State; a batch "
    << "step steps every avatar once (`step_batch`, TBB arena of the row's threads). Speed-up: against 1 thread "
    << "for the same batch size.\n\n"
    << r.describe();
  write_text(path, m.str());
}

}  // namespace sflsh
