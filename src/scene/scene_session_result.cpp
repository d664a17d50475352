// What a SceneSession writes to a SimulationResult: the constant header (every
// body's skin, the objects' and tools' surfaces, the tools' names) and one
// frame per call (skins, joints, object poses, every tool's pose, closure,
// force and torque, and the grasp and release events so far).
#include "sflsh/scene/scene_session.hpp"

#include "sflsh/sim/avatar_model.hpp"
#include "sflsh/sim/energies/contact_patch.hpp"
#include "scene/scene_session_impl.hpp"

namespace sflsh {
namespace {

/// The file name of a path (what results call the scene and the avatars).
std::string file_name(const std::string& path) {
  const size_t slash = path.find_last_of('/');
  return slash == std::string::npos ? path : path.substr(slash + 1);
}

}  // namespace

SimulationResult SceneSession::result_header() const {
  const Impl& m = *impl_;
  const CompiledScene& cs = m.compiled;
  SimulationResult r;
  r.motion = m.sc.path.empty() ? std::string("scene") : file_name(m.sc.path);
  r.dt = cs.h;
  r.bones_dynamic = cs.bodies[0].desc->bones_dynamic;
  r.newton_iters = m.sc.solver.newton_iterations;
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
  return r;
}

std::vector<Isometry> SceneSession::object_poses() const {
  const Impl& m = *impl_;
  const double t = m.sim->time();
  std::vector<Isometry> poses;
  for (const CompiledObject& o : m.compiled.objects) poses.push_back(m.object_pose(o, t));
  for (const ToolDriver& tool : m.tools)
    if (tool.tool().desc->has_shape) poses.push_back(tool.drawn_pose(t));
  for (const ToolDriver& tool : m.tools)
    for (const CompiledJaw& j : tool.tool().jaws) poses.push_back(tool.jaw_pose(j));
  return poses;
}

void SceneSession::record_frame(SimulationResult& r, double ms) const {
  const Impl& m = *impl_;
  const CompiledScene& cs = m.compiled;
  const Simulator& sim = *m.sim;
  const double t = m.k * cs.h;
  const int V = r.body_vertex_offsets.back();
  Points positions(V, 3), displacement(V, 3), joints(24 * int(cs.bodies.size()), 3);
  VecX reduced(0);
  for (size_t i = 0; i < cs.bodies.size(); ++i) {
    const int v0 = r.body_vertex_offsets[i], n = r.body_vertex_offsets[i + 1] - v0, k = cs.bodies[i].model_index;
    positions.middleRows(v0, n) = sim.posed_surface(k);
    displacement.middleRows(v0, n) = sim.soft_displacement(k);
    // The contact patches' dents (unposed), carried to the world by the skin's blend of bone rotations.
    const Avatar& a = *cs.bodies[i].avatar;
    const Points dent = patch_surface_displacement(a, m.report, k);
    for (int v = 0; v < n; ++v) {
      if (dent.row(v).isZero()) continue;
      const Mat3 A = skinning_rotation_blend(a.surface_weights.row(v), sim.state(k).bones);
      displacement.row(v0 + v) += dent.row(v);
      positions.row(v0 + v) += (A * dent.row(v).transpose()).transpose();
    }
    joints.middleRows(24 * int(i), 24) = sim.joints(k);
    const VecX& z = sim.state(k).z;
    VecX grown(reduced.size() + z.size());
    grown << reduced, z;
    reduced = std::move(grown);
  }
  const CompiledBody& b0 = cs.bodies[0];
  r.frame_time.push_back(t);
  r.frame_step_ms.push_back(ms);
  r.frame_positions.push_back(std::move(positions));
  r.frame_displacement.push_back(std::move(displacement));
  r.frame_joints.push_back(std::move(joints));
  r.frame_reduced.push_back(std::move(reduced));
  r.frame_target_pelvis.push_back(b0.target_pose(t).translation + b0.avatar->joints_rest.row(0).transpose());
  for (size_t i = 0; i < cs.objects.size(); ++i) r.objects[i].poses.push_back(m.object_pose(cs.objects[i], t));
  size_t next = cs.objects.size();
  for (const ToolDriver& tool : m.tools)
    if (tool.tool().desc->has_shape) r.objects[next++].poses.push_back(tool.drawn_pose(t));
  for (const ToolDriver& tool : m.tools)
    for (const CompiledJaw& j : tool.tool().jaws) r.objects[next++].poses.push_back(tool.jaw_pose(j));
  for (size_t i = 0; i < m.tools.size(); ++i) {
    const SceneToolState& ts = m.tools[i].state();
    r.tools[i].frames.push_back({m.tools[i].drawn_pose(t), ts.device.closure, ts.force, ts.torque});
  }
  r.tool_events = m.events;
  ++r.num_frames;
}

}  // namespace sflsh
