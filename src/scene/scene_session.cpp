#include "sflsh/scene/scene_session.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include "sflsh/core/error.hpp"
#include "sflsh/sim/finite_guard.hpp"
#include "sflsh/sim/skeleton_pose.hpp"
#include "scene/scene_session_impl.hpp"

namespace sflsh {
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
const std::vector<SceneToolEvent>& SceneSession::tool_events() const { return impl_->events; }

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
  require(m.tools.empty(), where, ": a checkpoint holds no tool (grasps, devices); the scene has ", m.tools.size());
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

int SceneSession::num_bodies() const { return int(impl_->compiled.bodies.size()); }
const std::string& SceneSession::body_name(int body) const { return impl_->compiled.bodies.at(body).desc->name; }
const Avatar& SceneSession::avatar(int body) const { return *impl_->compiled.bodies.at(body).avatar; }
int SceneSession::body_model_index(int body) const { return impl_->compiled.bodies.at(body).model_index; }
Points SceneSession::body_surface(int body) const { return impl_->sim->posed_surface(body_model_index(body)); }
Points SceneSession::body_displacement(int body) const {
  return impl_->sim->soft_displacement(body_model_index(body));
}
Points SceneSession::body_joints(int body) const { return impl_->sim->joints(body_model_index(body)); }
BodyPose SceneSession::body_target_pose(int body, double t) const {
  return impl_->compiled.bodies.at(body).target_pose(t);
}

int SceneSession::num_tools() const { return int(impl_->tools.size()); }
const std::string& SceneSession::tool_name(int tool) const { return impl_->tools.at(tool).name(); }
int SceneSession::tool_index(const std::string& name) const {
  std::string known;
  for (size_t i = 0; i < impl_->tools.size(); ++i) {
    if (impl_->tools[i].name() == name) return int(i);
    known += (known.empty() ? "" : ", ") + impl_->tools[i].name();
  }
  fail(impl_->sc.path, ": no tool named '", name, "' (tools: ", known.empty() ? "none" : known, ")");
}
const SceneToolState& SceneSession::tool_state(int tool) const { return impl_->tools.at(tool).state(); }
const CompiledTool& SceneSession::compiled_tool(int tool) const { return impl_->tools.at(tool).tool(); }
void SceneSession::set_device_pose(int tool, const teleop::PoseSample& sample) { impl_->tools.at(tool).push(sample); }
int SceneSession::stream_port(int tool) const { return impl_->tools.at(tool).stream_port(); }
std::string SceneSession::stream_counters(int tool) const { return impl_->tools.at(tool).stream_counters(); }

void SceneSession::end_feedback() {
  for (ToolDriver& t : impl_->tools) t.end_feedback();
}

std::vector<std::string> SceneSession::finish_recording() {
  std::vector<std::string> paths;
  for (ToolDriver& t : impl_->tools)
    if (std::string p = t.finish_recording(); !p.empty()) paths.push_back(std::move(p));
  return paths;
}

}  // namespace sflsh
