#include "sflsh/reference/scene_reference_run.hpp"

#include <iostream>

#include "sflsh/core/error.hpp"
#include "sflsh/core/interrupt.hpp"
#include "sflsh/core/progress.hpp"
#include "sflsh/core/timer.hpp"
#include "sflsh/scene/rigid_object.hpp"
#include "sflsh/scene/scene_session.hpp"
#include "sflsh/reference/full_fem.hpp"
#include "sflsh/sim/grasp_controller.hpp"

namespace sflsh {
namespace {

const std::string& scene_name(const SceneDescription& sc) {
  static const std::string unnamed = "scene";
  return sc.path.empty() ? unnamed : sc.path;
}

/// Whether contact between the body and `object` is on (contact.pairs).
bool collides(const ContactDescription& c, const std::string& body, const std::string& object) {
  if (c.all_pairs) return true;
  for (const auto& [a, b] : c.pairs)
    if ((a == body && b == object) || (a == object && b == body)) return true;
  return false;
}

}  // namespace

void check_scene_reference(const SceneDescription& sc) {
  const std::string& where = scene_name(sc);
  require(sc.bodies.size() == 1, where, ": --solver full runs one body; the scene has ", sc.bodies.size(),
          " (body-body contact has no full-FEM reference yet)");
  for (const RigidObjectDescription& o : sc.objects)
    require(o.kind != ObjectKind::Dynamic, where, ": objects '", o.name,
            "' is dynamic; --solver full takes static and kinematic objects only");
  for (const ToolDescription& t : sc.tools) {
    require(t.stream_port < 0, where, ": tools '", t.name, "' reads a live stream; --solver full runs offline");
    require(t.jaws.empty(), where, ": tools '", t.name, "' has jaws; --solver full has no jaw contact");
  }
}

namespace {

/// The scene as the reference runs it: refusals thrown, dynamic bones and
/// coupled tools made kinematic and friction dropped (each with a warning).
SceneDescription reference_scene(const SceneDescription& sc) {
  check_scene_reference(sc);
  const std::string& where = scene_name(sc);
  SceneDescription out = sc;
  if (out.bodies[0].bones_dynamic) {
    std::cerr << "warning: " << where << ": bodies '" << out.bodies[0].name
              << "': --solver full prescribes the bones from the motion (bones: dynamic runs as kinematic)\n";
    out.bodies[0].bones_dynamic = false;
  }
  for (ToolDescription& t : out.tools)
    if (t.coupled) {
      std::cerr << "warning: " << where << ": tools '" << t.name
                << "': --solver full moves the tool along its device's path (the coupling runs as kinematic)\n";
      t.coupled = false;
    }
  bool obstacles = !out.objects.empty();
  for (const ToolDescription& t : out.tools) obstacles = obstacles || t.has_shape;
  if (out.contact.friction > 0 && obstacles)
    std::cerr << "warning: " << where << ": --solver full is frictionless (contact.friction "
              << out.contact.friction << " is dropped)\n";
  return out;
}

/// A kinematic tool with a grasp, on the reference's skin (header comment).
struct ReferenceGrasp {
  int tool = 0;
  GraspController grasp;
  double hardness = 0, damping = 0;
  size_t first = 0, count = 0;  // its anchors in the step's FullFemAnchor list
};

/// Adds the scene's obstacles in contact with the body to `fem`: the result
/// header's objects (objects, then tools with a shape). Returns each
/// obstacle's index into r.objects.
std::vector<int> add_obstacles(const SceneDescription& sc, const std::string& body_name, const SimulationResult& r,
                               FullFem& fem) {
  std::vector<int> obstacle_object;
  auto add = [&](const std::string& name, const ShapeDescription& shape, ObjectKind kind) {
    if (!collides(sc.contact, body_name, name)) return;
    RigidObjectDescription d;
    d.name = name;
    d.shape = shape;
    d.kind = kind;
    FullFemObstacle ob{name, make_rigid_object(d).field, sc.contact.pressure_stiffness,
                       sc.contact.patch_spacing};
    fem.add_obstacle(std::move(ob));
    for (size_t i = 0; i < r.objects.size(); ++i)
      if (r.objects[i].name == name) obstacle_object.push_back(int(i));
    require(obstacle_object.size() == size_t(fem.num_obstacles()), name, ": not in the result's objects");
  };
  for (const RigidObjectDescription& o : sc.objects) add(o.name, o.shape, o.kind);
  for (const ToolDescription& t : sc.tools)
    if (t.has_shape) add(t.name, t.shape, ObjectKind::Kinematic);
  return obstacle_object;
}

/// The grasping tools on the reference's own skin over the step from t0:
/// each tool's grasp by the reduced run's rule at its device pose at t0
/// (`before`; the session has stepped to t0 + h), its anchors set on `fem`,
/// its grasp and release events appended to `events`.
void grasp_reference_skin(const SceneSession& session, const std::vector<teleop::PoseSample>& before, double t0,
                          std::vector<ReferenceGrasp>& grasps, FullFem& fem, std::vector<ToolEvent>& events) {
  const double h = session.dt();
  const std::string& body_name = session.body_name(0);
  const Simulator& sim = session.simulator();
  const int body = session.body_model_index(0);
  std::vector<FullFemAnchor> anchors;
  Points skin;  // the reference's skin at t, while a tool looks for something to grasp
  std::vector<AnchorPoint> points;
  for (size_t g = 0; g < grasps.size(); ++g) {
    ReferenceGrasp& rg = grasps[g];
    const teleop::PoseSample& now = before[g];
    const teleop::PoseSample& next = session.tool_state(rg.tool).device;
    const Isometry pose_now = pose_at(now.position, now.orientation);
    if (rg.grasp.seeking(now.closure) && skin.size() == 0) skin = fem.skin_points(fem.displacement());
    if (rg.grasp.update(t0, pose_now, now.closure, rg.grasp.seeking(now.closure) ? skin : Points(),
                        sim.model().bodies()[size_t(body)].avatar->surface_faces)) {
      const GraspEvent& ev = rg.grasp.log().back();
      events.push_back({ev.time, session.tool_name(rg.tool), body_name,
                        ev.kind == GraspEvent::Kind::Grasp ? "grasp" : "release", int(ev.points.size())});
    }
    anchor_points(frame_between(pose_now, pose_at(next.position, next.orientation), h), rg.grasp.anchors(), false,
                  points);
    rg.first = anchors.size();
    rg.count = points.size();
    for (const AnchorPoint& p : points)
      anchors.push_back({p.point, p.position, p.position - h * p.velocity, rg.hardness, rg.damping});
  }
  fem.set_anchors(std::move(anchors));
}

/// One reference step's forces: on each tool its shape's contact reaction
/// and its anchors' (`tool_forces`), each obstacle's contact into the
/// statistics and the result's contact frames (`contacts`, drawn at `poses`).
void collect_forces(const SceneSession& session, const FullFemReport& rep, const std::vector<ReferenceGrasp>& grasps,
                    const std::vector<Isometry>& poses, std::vector<Vec3>& tool_forces, SceneContactStats& st,
                    std::vector<ContactFrame>& contacts) {
  for (int i = 0; i < session.num_tools(); ++i) {
    Vec3 f = Vec3::Zero();
    for (size_t o = 0; o < rep.contacts.size(); ++o)
      if (rep.contacts[o].name == session.tool_name(i)) f -= rep.contacts[o].force;
    tool_forces[size_t(i)] = f;
  }
  for (const ReferenceGrasp& g : grasps)
    for (size_t i = g.first; i < g.first + g.count; ++i) tool_forces[size_t(g.tool)] -= rep.anchor_forces.at(i);
  for (size_t i = 0; i < rep.contacts.size(); ++i) {
    SceneContactStats::Pair& p = st.pairs[i];
    const FullFemContact& c = rep.contacts[i];
    p.last_force = c.force;
    p.max_force = std::max(p.max_force, c.force.norm());
    p.max_penetration = std::max(p.max_penetration, c.max_penetration);
    if (c.active_samples > 0) ++p.active_steps;
    contacts[i] = {c.force, poses.at(i).translation(), c.max_penetration, c.active_samples};
  }
}

}  // namespace

SimulationResult run_scene_reference(const SceneDescription& scene, const SceneReferenceOptions& opt,
                                     SceneContactStats* stats) {
  const SceneDescription sc = reference_scene(scene);
  SceneSessionOptions so;
  so.progress = false;
  // The session supplies the inputs (bones, object and tool poses) and the result's layout.
  SceneSession session(sc, so);
  const Simulator& sim = session.simulator();
  const int body = session.body_model_index(0);
  const std::string& body_name = session.body_name(0);
  FullFemOptions fo;
  fo.h = session.dt();
  fo.gravity = sc.solver.gravity;
  fo.max_iterations = opt.max_iterations;
  FullFem fem(sim.model().bodies()[size_t(body)].avatar, fo);
  fem.reset(sim.state(body).bones);

  SimulationResult r = session.result_header();
  const std::vector<int> obstacle_object = add_obstacles(sc, body_name, r, fem);

  std::vector<ReferenceGrasp> grasps;
  for (int i = 0; i < session.num_tools(); ++i) {
    const CompiledTool& tool = session.compiled_tool(i);
    if (!tool.desc->sensors.empty())
      grasps.push_back({i, GraspController(tool.grasp), tool.desc->hardness, tool.desc->damping});
  }
  std::vector<ToolEvent> tool_events;
  std::vector<Vec3> tool_forces(size_t(session.num_tools()), Vec3::Zero());

  SceneContactStats st;
  for (int i = 0; i < fem.num_obstacles(); ++i)
    st.pairs.push_back({"contact:" + r.objects[size_t(obstacle_object[size_t(i)])].name, body_name});
  // The result's contacts are the reference's obstacles (not the session's
  // reduced-model terms), each drawn at its obstacle's position (FullFemContact has no point).
  r.contacts.clear();
  std::vector<ContactFrame> contacts(st.pairs.size());
  for (size_t i = 0; i < st.pairs.size(); ++i) {
    r.contacts.push_back({st.pairs[i].term, body_name, {}});
    contacts[i].point = session.object_poses().at(size_t(obstacle_object[i])).translation();
  }
  auto record = [&](double ms) {
    FrameData fr = session.frame(ms);
    fr.contacts = contacts;
    for (size_t i = 0; i < fr.tools.size() && i < tool_forces.size(); ++i) {
      fr.tools[i].force = tool_forces[i];
      fr.tools[i].torque.setZero();  // the reference reports forces only
    }
    r.add_frame(std::move(fr));
    r.tool_events = tool_events;
    ++r.num_frames;
    r.frame_positions.back() = fem.posed_surface();
    r.frame_displacement.back() = fem.soft_displacement();
    r.frame_reduced.back().setZero();  // the reference has no reduced coordinates
  };
  record(0.0);
  const long steps = session.total_steps();
  const double frame_dt = 1.0 / sc.output.fps;
  double next_frame = frame_dt, ms_since_frame = 0;
  int steps_since_frame = 0, not_converged = 0;
  Progress progress("full-FEM reference of " + r.motion, steps);
  for (long k = 0; k < steps; ++k) {
    if (interrupt_signal()) throw_if_interrupted("at step " + std::to_string(k + 1) + " of " + std::to_string(steps));
    // The grasping tools' devices at t (before the session's step) and t + h.
    std::vector<teleop::PoseSample> before;
    for (const ReferenceGrasp& g : grasps) before.push_back(session.tool_state(g.tool).device);
    session.advance();
    if (!grasps.empty()) grasp_reference_skin(session, before, double(k) * session.dt(), grasps, fem, tool_events);
    const std::vector<Isometry> all = session.object_poses();
    std::vector<Isometry> poses;
    for (int i : obstacle_object) poses.push_back(all.at(size_t(i)));
    const double cpu0 = thread_cpu_ms();
    const FullFemReport rep = fem.step(sim.state(body).bones, poses);
    const double cpu_ms = thread_cpu_ms() - cpu0;
    const double t = (k + 1) * session.dt();
    if (!rep.converged) ++not_converged;
    collect_forces(session, rep, grasps, poses, tool_forces, st, contacts);
    StepReport sr;  // Newton to convergence: each step counts as accepted (non-converged ones are warned about)
    sr.accepted = 1;
    sr.iterations = rep.iterations;
    sr.energy_after = rep.energy;
    sr.grad_norm_before = rep.grad_norm_initial;
    sr.grad_norm_after = rep.grad_norm;
    sr.ms_total = rep.ms_total;
    sr.ms_solve = rep.ms_factorize;
    r.add_step(t, sr);
    ms_since_frame += rep.ms_total;
    ++steps_since_frame;
    if (t + 1e-9 >= next_frame) {
      record(ms_since_frame / steps_since_frame);
      next_frame += frame_dt;
      ms_since_frame = 0;
      steps_since_frame = 0;
    }
    if (opt.on_step) {
      std::vector<Isometry> tool_poses;
      for (int i = 0; i < session.num_tools(); ++i) tool_poses.push_back(session.tool_state(i).pose);
      opt.on_step({k + 1, t, &fem, &rep, &poses, &tool_forces, &tool_poses, cpu_ms});
    }
    if (opt.progress) progress.update(k + 1);
  }
  if (opt.progress) progress.finish();
  if (not_converged > 0)
    std::cerr << "warning: " << scene_name(sc) << ": the full-FEM Newton solve stopped at " << opt.max_iterations
              << " iterations before converging in " << not_converged << " of " << steps << " steps\n";
  if (stats) *stats = std::move(st);
  return r;
}

}  // namespace sflsh
