#include "sflsh/scene/scene_run.hpp"

#include <cmath>
#include <fstream>
#include <iomanip>
#include <map>
#include <set>
#include <sstream>

#include "sflsh/core/error.hpp"
#include "sflsh/core/interrupt.hpp"
#include "sflsh/core/progress.hpp"
#include "sflsh/io/atomic_output.hpp"
#include "sflsh/scene/scene_session.hpp"
#include "sflsh/sim/finite_guard.hpp"
#include "sflsh/sim/momentum.hpp"
#include "sflsh/sim/state_file.hpp"

namespace sflsh {

void SceneContactStats::write_tool_log(const std::string& path) const {
  io::AtomicOutput out(path);
  {
    std::ofstream o(out.temp_path());
    require(bool(o), path, ": cannot write the tool log");
    o << "time,tool,fx,fy,fz,anchors,max_stretch\n" << std::setprecision(9);
    for (const ToolStep& s : tool_steps)
      o << s.time << "," << s.tool << "," << s.force.x() << "," << s.force.y() << "," << s.force.z() << ","
        << s.anchors << "," << s.max_stretch << "\n";
    require(bool(o), path, ": writing the tool log failed");
  }
  out.commit();
}

std::string SceneContactStats::describe() const {
  std::ostringstream o;
  o << std::fixed;
  for (const ToolEvent& e : tool_events)
    o << "tool " << e.tool << " t = " << std::setprecision(3) << e.time << " s: " << e.kind << " " << e.points
      << " skin points of " << e.body << "\n";
  if (!tool_steps.empty()) {
    double fmax = 0, stretch = 0;
    for (const ToolStep& s : tool_steps) {
      fmax = std::max(fmax, s.force.norm());
      stretch = std::max(stretch, s.max_stretch);
    }
    o << "tools: peak force " << std::setprecision(2) << fmax << " N, largest anchor stretch "
      << stretch * 1e3 << " mm\n";
  }
  for (const Pair& p : pairs)
    o << "contact " << p.term << " on " << p.body << ": max penetration " << std::setprecision(2)
      << p.max_penetration * 1e3 << " mm, max force " << std::setprecision(1) << p.max_force << " N, in contact "
      << p.active_steps << " steps; at the end " << p.last_force.transpose() << " N\n";
  const double p0 = momentum_start.norm();
  o << std::setprecision(4) << "linear momentum: start " << p0 << " kg m/s, end " << momentum_end.norm()
    << " kg m/s (change " << std::scientific << std::setprecision(2) << (momentum_end - momentum_start).norm()
    << ")\n";
  return o.str();
}

namespace {

/// Gathers SceneContactStats step by step from the terms' reports and the tools' states.
class ContactStatsRecorder {
 public:
  explicit ContactStatsRecorder(const SceneSession& scene) : scene_(scene) {
    const Simulator& sim = scene.simulator();
    stats_.momentum_start = linear_momentum(sim.model(), sim.scene_state());
    // Tools' anchors and couplings: reported in tool_steps, not as contact pairs.
    for (int i = 0; i < scene.num_tools(); ++i) {
      const CompiledTool& t = scene.compiled_tool(i);
      tool_terms_.insert(t.anchor_terms.begin(), t.anchor_terms.end());
      if (t.coupling_term >= 0) tool_terms_.insert(t.coupling_term);
    }
  }

  void add_step(double t, const StepReport& rep) {
    for (int i = 0; i < scene_.num_tools(); ++i) {
      const SceneToolState& ts = scene_.tool_state(i);
      stats_.tool_steps.push_back({t, scene_.tool_name(i), ts.force, ts.anchors, ts.max_stretch});
    }
    // Contact figures from the terms' reports.
    for (SceneContactStats::Pair& p : stats_.pairs) p.last_force.setZero();  // inactive terms report nothing
    for (const TermQuantityReport& q : rep.quantities) {
      if (tool_terms_.count(q.term_index)) continue;
      const auto key = std::make_pair(q.term, q.body);
      auto [it, fresh] = pair_index_.try_emplace(key, stats_.pairs.size());
      if (fresh) stats_.pairs.push_back({q.term, scene_.simulator().model().bodies()[q.body].name});
      SceneContactStats::Pair& p = stats_.pairs[it->second];
      if (q.name == "max_penetration" || q.name == "max_overlap") {
        p.max_penetration = std::max(p.max_penetration, q.value[0]);
        if (q.value[0] > 0) ++p.active_steps;
      } else if (q.name == "force" && q.value.size() == 3) {
        p.last_force = Vec3(q.value[0], q.value[1], q.value[2]);
        p.max_force = std::max(p.max_force, p.last_force.norm());
      }
    }
  }

  SceneContactStats finish() {
    stats_.tool_events = scene_.tool_events();
    const Simulator& sim = scene_.simulator();
    stats_.momentum_end = linear_momentum(sim.model(), sim.scene_state());
    return std::move(stats_);
  }

 private:
  const SceneSession& scene_;
  SceneContactStats stats_;
  std::map<std::pair<std::string, int>, size_t> pair_index_;
  std::set<int> tool_terms_;
};

/// Makes the output frames: every one to on_frame, kept in the result
/// (keep_frames), counted, with the first body's pelvis against its motion's.
class FrameRecorder {
 public:
  FrameRecorder(const SceneSession& scene, const SceneRunOptions& options, SimulationResult& result)
      : scene_(scene), options_(options), r_(result), frame_dt_(1.0 / scene.scene().output.fps) {
    const double t = scene.simulator().time();
    next_frame_ = (std::floor(t / frame_dt_ + 1e-9) + 1) * frame_dt_;
    record(0.0);
  }

  /// After a step ending at time t taking `ms`: a frame when one is due.
  void add_step(double t, double ms) {
    ms_since_frame_ += ms;
    ++steps_since_frame_;
    if (t + 1e-9 < next_frame_) return;
    record(ms_since_frame_ / steps_since_frame_);
    next_frame_ += frame_dt_;
    ms_since_frame_ = 0;
    steps_since_frame_ = 0;
  }

 private:
  void record(double ms) {
    FrameData fr = scene_.frame(ms);
    const double pelvis_error = (fr.joints.row(0).transpose() - fr.target_pelvis).norm();
    pelvis_error_sum_ += pelvis_error;
    r_.pelvis_error_max = std::max(r_.pelvis_error_max, pelvis_error);
    ++r_.pelvis_frames;
    r_.pelvis_error_mean = pelvis_error_sum_ / r_.pelvis_frames;
    ++r_.num_frames;
    r_.tool_events = scene_.tool_events();
    if (options_.on_frame) options_.on_frame(fr);
    if (options_.keep_frames) r_.add_frame(std::move(fr));
  }

  const SceneSession& scene_;
  const SceneRunOptions& options_;
  SimulationResult& r_;
  const double frame_dt_;
  double next_frame_ = 0, ms_since_frame_ = 0, pelvis_error_sum_ = 0;
  int steps_since_frame_ = 0;
};

}  // namespace

SimulationResult run_scene(SceneSession& scene, const SceneRunOptions& opt, SceneContactStats* stats) {
  if (!opt.resume.empty()) scene.resume(read_state(opt.resume, scene.simulator().model()), opt.resume);
  const long steps = scene.total_steps();
  SimulationResult r = scene.result_header();
  FrameRecorder frames(scene, opt, r);
  ContactStatsRecorder contact(scene);
  Progress progress("simulating " + r.motion, steps);
  while (scene.steps_done() < steps) {
    const long k = scene.steps_done();
    if (interrupt_signal()) throw_if_interrupted("at step " + std::to_string(k + 1) + " of " + std::to_string(steps));
    const StepReport* step_report = nullptr;
    try {
      step_report = &scene.advance();
    } catch (const NonFiniteError& e) {
      // Keep the frames made so far, marked incomplete (no frame of this step).
      if (opt.progress) progress.finish();
      r.incomplete = true;
      r.stop_reason = e.what();
      throw SimulationStopped(e.what(), std::move(r));
    }
    const StepReport& rep = *step_report;
    const double t = (k + 1) * scene.dt();
    contact.add_step(t, rep);
    r.add_step(t, rep);
    if (opt.on_step) opt.on_step(scene.simulator(), rep);
    frames.add_step(t, rep.ms_total);
    if (opt.progress) progress.update(k + 1);
  }
  if (opt.progress) progress.finish();
  r.tool_events = scene.tool_events();  // also those after the last frame
  if (stats) *stats = contact.finish();
  if (!opt.checkpoint.empty())
    write_state(opt.checkpoint, scene.simulator().model(), scene.simulator().scene_state());
  return r;
}

SimulationResult run_scene(const SceneDescription& sc, const SceneRunOptions& opt, SceneContactStats* stats) {
  SceneSessionOptions so;
  so.progress = opt.progress;
  so.body_push_limit = opt.body_push_limit;
  so.inject_nan_at_step = opt.inject_nan_at_step;
  SceneSession scene(sc, so);
  return run_scene(scene, opt, stats);
}

}  // namespace sflsh
