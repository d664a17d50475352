// The offline run loop (run_scene) and what it steps: a scene built, advanced
// a step at a time, reset, rescaled and resumed (SceneSession; what it shows is
// in scene_frames.cpp, its tools in tool_driver.cpp). The contact figures and
// the tool log of a run are here too.
#include "sflsh/scene/scene_run.hpp"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <limits>
#include <map>
#include <set>
#include <sstream>

#include "scene/scene_run_state.hpp"
#include "sflsh/core/error.hpp"
#include "sflsh/core/interrupt.hpp"
#include "sflsh/core/progress.hpp"
#include "sflsh/io/atomic_output.hpp"
#include "sflsh/scene/scene_checkpoint.hpp"
#include "sflsh/scene/scene_session.hpp"
#include "sflsh/sim/finite_guard.hpp"
#include "sflsh/sim/momentum.hpp"
#include "sflsh/sim/skeleton_pose.hpp"
#include "sflsh/sim/state_file.hpp"

namespace sflsh {

// Stepping a scene: building it, advancing it a step, resetting, rescaling, resuming.

namespace {

bool all_finite(const std::vector<Isometry>& bones) {
  for (const Isometry& b : bones)
    if (!b.matrix().allFinite()) return false;
  return true;
}

}  // namespace

void SceneSession::Impl::start() {
  const ToolDriverOptions to{opt.progress, opt.open_streams, opt.record_dir, opt.replay_dir, sc.path};
  tools.reserve(compiled.tools.size());
  for (const CompiledTool& t : compiled.tools) tools.emplace_back(t, int(compiled.bodies.size()), to);
  sim = std::make_unique<Simulator>(compiled.model);
  State s = compiled.initial;
  for (ToolDriver& t : tools) t.start(s);
  sim->set_state(s);
  in.bodies.resize(sim->model().bodies().size());
  initial = s;
  stiffness.assign(compiled.bodies.size(), 1.0);
}

SceneSession::SceneSession(const SceneDescription& scene, const SceneSessionOptions& options)
    : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  m.sc = scene;
  m.opt = options;
  m.compiled = compile_scene(m.sc, {options.progress, options.body_push_limit});
  m.start();
}

SceneSession::SceneSession(std::shared_ptr<const Avatar> avatar, const MotionClip& motion, const RunOptions& options)
    : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  BodyDescription body;
  body.name = "avatar";
  body.motion = motion.name;
  body.bones_dynamic = options.sim.bones_dynamic;
  m.sc.bodies.push_back(body);
  m.sc.solver.dt = options.sim.h;
  m.sc.solver.seconds = options.seconds;
  m.sc.solver.newton_iterations = options.sim.newton.iterations;
  m.sc.solver.iterations_after_damping = options.sim.newton.iterations_after_damping;
  m.sc.solver.line_search = options.sim.newton.line_search;
  m.sc.solver.nonlinearity_tolerance = options.sim.newton.nonlinearity_tolerance;
  m.sc.solver.gravity = options.sim.gravity;
  m.sc.solver.damping = options.sim.damping;
  m.sc.output.fps = options.output_fps;
  m.opt.progress = options.progress;
  m.opt.inject_nan_at_step = options.inject_nan_at_step;
  m.compiled = compile_avatar_motion(m.sc, std::move(avatar), motion, options.sim, options.skeleton,
                                     options.start_at_rest);
  m.start();
}

SceneSession::~SceneSession() = default;

const SceneDescription& SceneSession::scene() const { return impl_->sc; }
const std::string& SceneSession::name() const { return impl_->compiled.name; }
double SceneSession::dt() const { return impl_->compiled.h; }
double SceneSession::time() const { return impl_->sim->time(); }
long SceneSession::steps_done() const { return impl_->k; }
double SceneSession::seconds() const { return impl_->compiled.seconds; }
long SceneSession::total_steps() const { return impl_->compiled.steps; }
const StepReport& SceneSession::last_report() const { return impl_->report; }
const Simulator& SceneSession::simulator() const { return *impl_->sim; }

void SceneSession::reset() {
  Impl& m = *impl_;
  m.k = m.first_k = 0;
  m.report = StepReport{};
  m.events.clear();
  m.in = StepInputs{};
  m.in.bodies.resize(m.sim->model().bodies().size());
  for (ToolDriver& t : m.tools) t.reset();
  State s = m.initial;
  for (ToolDriver& t : m.tools) t.start(s);
  m.sim->set_state(s);  // a copy: fresh term caches, as in a new session
}

void SceneSession::set_stiffness_scale(double scale, int body) {
  Impl& m = *impl_;
  require(std::isfinite(scale) && scale > 0, "stiffness scale ", scale, ": expected a finite value > 0");
  require(body >= -1 && body < num_bodies(), "stiffness scale: body ", body, ", expected -1 (all) or 0..",
          num_bodies() - 1);
  if (body < 0)
    std::fill(m.stiffness.begin(), m.stiffness.end(), scale);
  else
    m.stiffness[size_t(body)] = scale;
  const State keep = m.sim->scene_state();
  // The same Simulator object: references to it stay valid.
  *m.sim = Simulator(model_with_stiffness(m.compiled.model, m.compiled.bodies, m.stiffness));
  m.sim->set_state(keep);
}

void SceneSession::resume(const State& state, const std::string& where) {
  Impl& m = *impl_;
  require(m.tools.empty(), where, ": a State holds no tool's grasp; the scene has ", m.tools.size(),
          " tool(s): resume from the checkpoint file (SceneSession::resume(path))");
  resume_at(state, where);
}

namespace {
/// What each tool holds now, for a checkpoint (scene_checkpoint.hpp).
std::vector<ToolCheckpoint> tool_checkpoints(const std::vector<ToolDriver>& tools) {
  std::vector<ToolCheckpoint> out;
  for (const ToolDriver& t : tools) out.push_back({t.name(), t.grasped()});
  return out;
}
}  // namespace

void SceneSession::resume(const std::string& path) {
  Impl& m = *impl_;
  std::vector<ToolCheckpoint> tools = tool_checkpoints(m.tools);
  std::vector<int> skin;
  for (const CompiledBody& b : m.compiled.bodies) skin.push_back(int(b.avatar->surface_rest.rows()));
  const State state = read_scene_checkpoint(path, m.sim->model(), tools, skin);
  for (ToolDriver& t : m.tools) t.reset();
  resume_at(state, path);
  for (size_t i = 0; i < m.tools.size(); ++i) m.tools[i].resume(*m.sim, state.time, std::move(tools[i].grasps));
}

void SceneSession::write_checkpoint(const std::string& path) const {
  const Impl& m = *impl_;
  write_scene_checkpoint(path, m.sim->model(), m.sim->scene_state(), tool_checkpoints(m.tools));
}

void SceneSession::resume_at(const State& state, const std::string& where) {
  Impl& m = *impl_;
  m.sim->set_state(state);
  const double h = m.compiled.h, time = m.sim->time();
  const long k = std::lround(time / h);
  require(std::abs(time - k * h) <= 1e-9 * std::max(1.0, time), where, ": the checkpoint's time ", time,
          " s is not a whole number of steps of ", h, " s");
  require(k <= m.compiled.steps, where, ": the checkpoint is at ", time, " s, past the run's end at ",
          m.compiled.steps * h, " s");
  m.k = m.first_k = k;
}

double SceneSession::stiffness_scale(int body) const { return impl_->stiffness.at(size_t(body)); }

const StepReport& SceneSession::advance() {
  Impl& m = *impl_;
  Simulator& sim = *m.sim;
  const CompiledScene& cs = m.compiled;
  const double h = cs.h;
  const long k = m.k;
  const double t = (k + 1) * h;
  for (const CompiledBody& b : cs.bodies) {
    BodyTargets& bt = m.in.bodies[b.model_index];
    bt.pose = b.target_pose(t);
    bt.bones = target_bones(*b.avatar, bt.pose);
  }
  std::vector<Isometry>& first_bones = m.in.bodies[cs.bodies[0].model_index].bones;
  if (k + 1 == m.opt.inject_nan_at_step)  // test only (the pose terms check their own input)
    first_bones[0].translation().x() = std::numeric_limits<double>::quiet_NaN();
  for (const CompiledObject& o : cs.objects) {
    if (o.model_index >= 0) continue;
    m.in.frames[o.frame] = frame_between(object_pose_at(*o.desc, t - h), object_pose_at(*o.desc, t), h);
  }
  for (ToolDriver& tool : m.tools) tool.drive(sim, cs.bodies, t, h, m.in, m.events);
  try {
    m.report = sim.step(m.in);
    m.k = k + 1;
    // Stops on NaN/Inf, naming the step, the term and the body (sim/finite_guard.hpp).
    require_finite_step(sim.model(), sim.scene_state(), m.report, k + 1, cs.name);
  } catch (const NonFiniteError&) {
    throw;
  } catch (const Error& e) {
    // The Newton step refuses a non-finite configuration itself (before any term is named).
    if (all_finite(first_bones)) throw;
    std::ostringstream why;
    why << cs.name << ": non-finite value at step " << k + 1 << " (t = " << t << " s): body '"
        << sim.model().bodies().at(cs.bodies[0].model_index).name << "': a target bone is not finite (" << e.what()
        << "); stopped";
    throw NonFiniteError(why.str(), k + 1, {});
  }
  const StepReport& rep = m.report;
  const std::string& path = cs.name;
  for (ToolDriver& tool : m.tools) tool.feel(sim, rep, t);
  for (const CompiledBody& b : cs.bodies)
    if (!sim.state(b.model_index).z.allFinite() || !sim.state(b.model_index).bones[0].matrix().allFinite())
      fail(path, ": body '", b.desc->name, "' became non-finite at step ", k + 1, " (t = ", t,
           " s); try a smaller solver.dt or lower contact stiffness");
  for (const CompiledObject& o : cs.objects)
    if (o.model_index >= 0 && !sim.state(o.model_index).bones[0].matrix().allFinite())
      fail(path, ": object '", o.desc->name, "' became non-finite at step ", k + 1, " (t = ", t, " s)");
  for (const ToolDriver& tool : m.tools)
    if (!tool.state().pose.matrix().allFinite())
      fail(path, ": tool '", tool.name(), "' became non-finite at step ", k + 1, " (t = ", t, " s)");
  return rep;
}

void SceneContactStats::write_tool_log(const std::string& path) const {
  io::write_text_file(path, [&](std::ostream& o) {
    o << "time,tool,fx,fy,fz,anchors,max_stretch\n" << std::setprecision(9);
    for (const ToolStep& s : tool_steps)
      o << s.time << "," << s.tool << "," << s.force.x() << "," << s.force.y() << "," << s.force.z() << ","
        << s.anchors << "," << s.max_stretch << "\n";
  });
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

// The run loop: frames, contact figures, stepping to the end.

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
  if (!opt.resume.empty()) scene.resume(opt.resume);
  const long steps = scene.total_steps();
  SimulationResult r = scene.result_header();
  FrameRecorder frames(scene, opt, r);
  ContactStatsRecorder contact(scene);
  // Every body's bones, at the start (t − h, t) and after each step (SimulationResult::step_bones).
  auto bones = [&](bool previous) {
    std::vector<Isometry> out;
    for (int b = 0; b < scene.num_bodies(); ++b) {
      const Simulator& sim = scene.simulator();
      const int k = scene.body_model_index(b);
      const std::vector<Isometry>& g = previous ? sim.previous_state(k).bones : sim.state(k).bones;
      out.insert(out.end(), g.begin(), g.end());
    }
    return out;
  };
  r.start_bones = {bones(true), bones(false)};
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
    r.step_bones.push_back(bones(false));
    if (opt.on_step) opt.on_step(scene.simulator(), rep);
    frames.add_step(t, rep.ms_total);
    if (opt.progress) progress.update(k + 1);
  }
  if (opt.progress) progress.finish();
  r.tool_events = scene.tool_events();  // also those after the last frame
  if (stats) *stats = contact.finish();
  if (!opt.checkpoint.empty())
    scene.write_checkpoint(opt.checkpoint);
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
