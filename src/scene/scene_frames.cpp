// What a scene shows of itself (SceneSession): the result's constant header
// (every body's skin, the objects' and tools' surfaces, the tools' names), its
// output frames (skins, joints, object poses, every tool's pose, closure,
// force and torque, every contact term's force, point, depth and samples, and
// the grasp and release events so far) and the bodies' current surfaces and
// joints.
#include "sflsh/scene/scene_session.hpp"

#include "sflsh/sim/avatar_model.hpp"
#include "sflsh/sim/energies/contact_patch.hpp"
#include "sflsh/sim/skeleton_pose.hpp"
#include "scene/scene_run_state.hpp"

namespace sflsh {
namespace {

/// The file name of a path (what results call the scene and the avatars).
std::string file_name(const std::string& path) {
  const size_t slash = path.find_last_of('/');
  return slash == std::string::npos ? path : path.substr(slash + 1);
}

}  // namespace

std::vector<Isometry> SceneSession::Impl::object_poses(double t) const {
  std::vector<Isometry> poses;
  for (const CompiledObject& o : compiled.objects) poses.push_back(object_pose(o, t));
  for (const ToolDriver& tool : tools)
    if (tool.tool().desc->has_shape) poses.push_back(tool.drawn_pose(t));
  for (const ToolDriver& tool : tools)
    for (const CompiledJaw& j : tool.tool().jaws) poses.push_back(tool.jaw_pose(j));
  return poses;
}

SimulationResult SceneSession::result_header() const {
  const Impl& m = *impl_;
  const CompiledScene& cs = m.compiled;
  SimulationResult r;
  r.motion = cs.one_avatar ? cs.name : m.sc.path.empty() ? std::string("scene") : file_name(m.sc.path);
  r.dt = cs.h;
  r.bones_dynamic = cs.bodies[0].desc->bones_dynamic;
  r.newton_iters = m.sc.solver.newton_iterations;
  if (cs.one_avatar) {
    r.faces = cs.bodies[0].avatar->surface_faces;
    r.surface_rest = cs.bodies[0].avatar->surface_rest;
    return r;
  }
  r.body_vertex_offsets.push_back(0);
  std::string names;
  int V = 0, F = 0;
  for (const CompiledBody& b : cs.bodies) {
    V += int(b.avatar->surface_rest.rows());
    F += int(b.avatar->surface_faces.rows());
  }
  r.surface_rest.resize(V, 3);
  r.faces.resize(F, 3);
  V = F = 0;
  for (const CompiledBody& b : cs.bodies) {
    r.surface_rest.middleRows(V, b.avatar->surface_rest.rows()) = b.avatar->surface_rest;
    r.faces.middleRows(F, b.avatar->surface_faces.rows()) = b.avatar->surface_faces.array() + V;
    V += int(b.avatar->surface_rest.rows());
    F += int(b.avatar->surface_faces.rows());
    r.body_names.push_back(b.desc->name);
    r.body_vertex_offsets.push_back(V);
    names += (names.empty() ? "" : ", ") + b.desc->name + " (" + file_name(b.desc->avatar) + ")";
  }
  r.avatar = names;
  for (const CompiledObject& o : cs.objects)
    r.objects.push_back({o.desc->name, shape_type_name(o.desc->shape.type), object_kind_name(o.desc->kind),
                         o.model.surface.vertices, o.model.surface.faces, {}});
  for (const CompiledTool& t : cs.tools)
    if (t.desc->has_shape)
      r.objects.push_back({t.desc->name, shape_type_name(t.desc->shape.type), t.coupled() ? "dynamic" : "kinematic",
                           t.shape.surface.vertices, t.shape.surface.faces, {}});
  for (const CompiledTool& t : cs.tools)
    for (size_t j = 0; j < t.jaws.size(); ++j)
      r.objects.push_back({t.jaws[j].name, shape_type_name(t.desc->jaws[j].shape.type),
                           t.coupled() ? "dynamic" : "kinematic", t.jaws[j].model.surface.vertices,
                           t.jaws[j].model.surface.faces, {}});
  for (const CompiledTool& t : cs.tools) r.tools.push_back({t.desc->name, {}});
  const Model& model = m.sim->model();
  for (int i : cs.contact_terms) {
    const Model::BoundTerm& t = model.terms()[size_t(i)];
    r.contacts.push_back({t.term->name(), model.bodies()[size_t(t.bodies[0])].name, {}});
  }
  return r;
}

std::vector<ContactFrame> SceneSession::Impl::contact_frames(const std::vector<Isometry>& poses) const {
  const Model& model = sim->model();
  std::vector<ContactFrame> out;
  for (int i : compiled.contact_terms) {
    const Model::BoundTerm& t = model.terms()[size_t(i)];
    ContactFrame c;
    bool has_point = false;
    for (const TermQuantityReport& q : report.quantities) {
      if (q.term_index != i) continue;
      if (q.name == "force" && q.value.size() == 3) c.force = Vec3(q.value[0], q.value[1], q.value[2]);
      if (q.name == "contact_point" && q.value.size() == 3) {
        c.point = Vec3(q.value[0], q.value[1], q.value[2]);
        has_point = true;
      }
      if ((q.name == "max_penetration" || q.name == "max_overlap") && q.value.size() == 1) c.max_penetration = q.value[0];
      if ((q.name == "active_samples" || q.name == "overlapping_pairs") && q.value.size() == 1) c.active = int(q.value[0]);
    }
    if (!has_point) c.point = fallback_contact_point(t, poses);
    out.push_back(c);
  }
  return out;
}

Vec3 SceneSession::Impl::fallback_contact_point(const Model::BoundTerm& t, const std::vector<Isometry>& poses) const {
  // "contact:<object>": the object's (a tool's shape's, a jaw's) position, in
  // object_poses' order; any other term: its body's pelvis.
  const std::string name = t.term->name(), prefix = "contact:";
  if (name.compare(0, prefix.size(), prefix) == 0) {
    const std::string object = name.substr(prefix.size());
    size_t k = 0;
    for (const CompiledObject& o : compiled.objects) {
      if (o.desc->name == object && k < poses.size()) return poses[k].translation();
      ++k;
    }
    for (const CompiledTool& tool : compiled.tools)
      if (tool.desc->has_shape) {
        if (tool.desc->name == object && k < poses.size()) return poses[k].translation();
        ++k;
      }
    for (const CompiledTool& tool : compiled.tools)
      for (const CompiledJaw& j : tool.jaws) {
        if (j.name == object && k < poses.size()) return poses[k].translation();
        ++k;
      }
  }
  return sim->joints(t.bodies[0]).row(0).transpose();
}

std::vector<Isometry> SceneSession::object_poses() const { return impl_->object_poses(impl_->sim->time()); }

FrameData SceneSession::frame(double ms) const {
  const Impl& m = *impl_;
  const CompiledScene& cs = m.compiled;
  const Simulator& sim = *m.sim;
  FrameData fr;
  // The run's first frame has the state's own time (a checkpoint's may differ
  // from k·h in the last bits), later ones the step's k·h.
  fr.time = m.k == m.first_k ? sim.time() : m.k * cs.h;
  fr.step_ms = ms;
  int V = 0;
  for (const CompiledBody& b : cs.bodies) V += int(b.avatar->surface_rest.rows());
  fr.positions.resize(V, 3);
  fr.displacement.resize(V, 3);
  fr.joints.resize(24 * int(cs.bodies.size()), 3);
  fr.reduced.resize(0);
  int v0 = 0;
  for (size_t i = 0; i < cs.bodies.size(); ++i) {
    const Avatar& a = *cs.bodies[i].avatar;
    const int n = int(a.surface_rest.rows()), k = cs.bodies[i].model_index;
    fr.positions.middleRows(v0, n) = sim.posed_surface(k);
    fr.displacement.middleRows(v0, n) = sim.soft_displacement(k);
    // The contact patches' dents (unposed), carried to the world by the skin's blend of bone rotations.
    const Points dent = patch_surface_displacement(a, m.report, k);
    for (int v = 0; v < n; ++v) {
      if (dent.row(v).isZero()) continue;
      const Mat3 A = skinning_rotation_blend(a.surface_weights.row(v), sim.state(k).bones);
      fr.displacement.row(v0 + v) += dent.row(v);
      fr.positions.row(v0 + v) += (A * dent.row(v).transpose()).transpose();
    }
    fr.joints.middleRows(24 * int(i), 24) = sim.joints(k);
    const VecX& z = sim.state(k).z;
    VecX grown(fr.reduced.size() + z.size());
    grown << fr.reduced, z;
    fr.reduced = std::move(grown);
    v0 += n;
  }
  // The first body's motion pelvis: G_0 J̄_0 of its target bones, as /frames/joints puts the simulated one.
  const CompiledBody& b0 = cs.bodies[0];
  fr.target_pelvis = target_bones(*b0.avatar, b0.target_pose(fr.time))[0] * Vec3(b0.avatar->joints_rest.row(0).transpose());
  fr.object_poses = m.object_poses(fr.time);
  fr.tools = m.tool_frames(fr.time);
  fr.contacts = m.contact_frames(fr.object_poses);
  return fr;
}

std::vector<ToolFrame> SceneSession::Impl::tool_frames(double t) const {
  std::vector<ToolFrame> out;
  for (const ToolDriver& tool : tools) {
    const SceneToolState& ts = tool.state();
    out.push_back({tool.drawn_pose(t), ts.device.closure, ts.force, ts.torque});
  }
  return out;
}

std::vector<ToolFrame> SceneSession::tool_frames() const { return impl_->tool_frames(impl_->sim->time()); }
std::vector<ContactFrame> SceneSession::contact_frames() const {
  return impl_->contact_frames(impl_->object_poses(impl_->sim->time()));
}

void SceneSession::record_frame(SimulationResult& r, double ms) const {
  r.add_frame(frame(ms));
  r.tool_events = impl_->events;
  ++r.num_frames;
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

}  // namespace sflsh
