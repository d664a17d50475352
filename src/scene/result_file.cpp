#include "sflsh/scene/result_file.hpp"

#include <algorithm>
#include <sstream>

#include "scene/result_file_format.hpp"
#include "sflsh/core/error.hpp"
#include "sflsh/scene/result_contacts.hpp"

namespace sflsh {

using result_file_detail::check_scene;
using result_file_detail::object_group;
using result_file_detail::pose_to_row;
using result_file_detail::tool_group;

ResultScene result_scene(const SimulationResult& r) {
  ResultScene s{r.body_names, r.body_vertex_offsets, r.objects, {}, r.contacts};
  for (ObjectTrack& t : s.objects) t.poses.clear();
  for (const ToolTrack& t : r.tools) s.tool_names.push_back(t.name);
  for (ContactTrack& c : s.contacts) c.frames.clear();
  return s;
}

int num_bodies(const SimulationResult& r) { return r.body_names.empty() ? 1 : int(r.body_names.size()); }

std::string describe_scene_parts(const SimulationResult& r) {
  std::ostringstream o;
  if (!r.body_names.empty()) {
    o << "bodies:";
    for (size_t b = 0; b < r.body_names.size(); ++b) {
      o << (b ? ", " : " ") << r.body_names[b];
      if (r.body_vertex_offsets.size() == r.body_names.size() + 1)
        o << " (" << r.body_vertex_offsets[b + 1] - r.body_vertex_offsets[b] << " skin vertices)";
    }
    o << "\n";
  }
  if (!r.objects.empty()) {
    o << "objects:";
    for (size_t i = 0; i < r.objects.size(); ++i)
      o << (i ? ", " : " ") << r.objects[i].name << " (" << r.objects[i].shape << ", " << r.objects[i].kind << ")";
    o << "\n";
  }
  return o.str();
}

ResultWriter::ResultWriter(const std::string& path, const Triangles& faces, const Points& surface_rest,
                           int num_reduced, bool target_pelvis, const ResultScene& scene)
    : target_pelvis_(target_pelvis) {
  const std::int64_t V = surface_rest.rows();
  require(faces.rows() == 0 || (faces.minCoeff() >= 0 && faces.maxCoeff() < V), path,
          ": skin face indices must lie in [0, ", V, ")");
  check_scene(scene, V, path);
  file_ = std::make_unique<io::Hdf5File>(path, io::Hdf5File::Mode::Write);
  num_vertices_ = V;
  num_joints_ = 24 * Eigen::Index(std::max<size_t>(1, scene.body_names.size()));
  num_reduced_ = num_reduced;
  auto& f = *file_;
  f.write_matrix("/surface/faces", faces);
  f.write_matrix("/surface/rest", surface_rest);
  if (!scene.body_names.empty()) {
    f.write_strings("/bodies/names", scene.body_names);
    f.write_nd("/bodies/vertex_offsets", scene.body_vertex_offsets.data(),
               {std::int64_t(scene.body_vertex_offsets.size())});
  }
  for (size_t o = 0; o < scene.objects.size(); ++o) {
    const ObjectTrack& t = scene.objects[o];
    const std::string g = object_group(o);
    f.write_string(g + "/name", t.name);
    f.write_string(g + "/shape", t.shape);
    f.write_string(g + "/kind", t.kind);
    f.write_matrix(g + "/vertices", t.vertices);
    f.write_matrix(g + "/faces", t.faces);
    object_names_.push_back(t.name);
  }
  for (size_t t = 0; t < scene.tool_names.size(); ++t) f.write_string(tool_group(t) + "/name", scene.tool_names[t]);
  tool_names_ = scene.tool_names;
  contacts_ = scene.contacts;
  for (ContactTrack& c : contacts_) c.frames.clear();
  create_contact_datasets(f, contacts_);
  f.create_appendable("/frames/time", {});
  f.create_appendable("/frames/step_ms", {});
  f.create_appendable("/frames/positions", {V, 3}, true);
  f.create_appendable("/frames/displacement", {V, 3}, true);
  f.create_appendable("/frames/joints", {num_joints_, 3});
  f.create_appendable("/frames/reduced", {num_reduced});
  if (target_pelvis_) f.create_appendable("/frames/target_pelvis", {3});
  if (!object_names_.empty()) f.create_appendable("/frames/object_poses", {std::int64_t(object_names_.size()), 7});
  if (const std::int64_t T = std::int64_t(tool_names_.size()); T > 0) {
    f.create_appendable("/frames/tool_poses", {T, 7});
    f.create_appendable("/frames/tool_closure", {T});
    f.create_appendable("/frames/tool_force", {T, 3});
    f.create_appendable("/frames/tool_torque", {T, 3});
  }
}

ResultWriter::~ResultWriter() = default;

void ResultWriter::add_frame(const FrameData& fr) {
  auto& f = *file_;
  const std::string at = f.path() + ": frame " + std::to_string(frames_);
  require(fr.positions.rows() == num_vertices_ && fr.displacement.rows() == num_vertices_, at, ": positions/displacement have ",
          fr.positions.rows(), "/", fr.displacement.rows(), " rows, expected ", num_vertices_, " skin vertices");
  require(fr.joints.rows() == num_joints_, at, ": joints has ", fr.joints.rows(), " rows, expected ", num_joints_,
          " (24 per body)");
  require(fr.reduced.size() == num_reduced_, at, ": reduced has ", fr.reduced.size(), " entries, expected ", num_reduced_);
  require(fr.object_poses.size() == object_names_.size(), at, ": ", fr.object_poses.size(), " object poses for ",
          object_names_.size(), " objects");
  // Last line of defence: a result file never holds NaN/Inf (the run's guard,
  // sim/finite_guard.hpp, stops before such a frame is made).
  for (const auto& [name, ok] : {std::pair<const char*, bool>{"positions", fr.positions.allFinite()},
                                 {"displacement", fr.displacement.allFinite()}, {"joints", fr.joints.allFinite()},
                                 {"reduced", fr.reduced.allFinite()}, {"target_pelvis", fr.target_pelvis.allFinite()},
                                 {"time", std::isfinite(fr.time)}})
    require(ok, at, ": ", name, " holds a non-finite value; not written");
  require(fr.tools.size() == tool_names_.size(), at, ": ", fr.tools.size(), " tool frames for ", tool_names_.size(),
          " tools");
  require(fr.contacts.size() == contacts_.size(), at, ": ", fr.contacts.size(), " contact frames for ",
          contacts_.size(), " contacts");
  std::vector<double> poses(7 * object_names_.size());
  for (size_t o = 0; o < object_names_.size(); ++o)
    pose_to_row(fr.object_poses[o], &poses[7 * o], at + ": the pose of object '" + object_names_[o] + "'");
  f.append("/frames/time", &fr.time);
  f.append("/frames/step_ms", &fr.step_ms);
  f.append("/frames/positions", fr.positions.data());
  f.append("/frames/displacement", fr.displacement.data());
  f.append("/frames/joints", fr.joints.data());
  f.append("/frames/reduced", fr.reduced.data());
  if (target_pelvis_) f.append("/frames/target_pelvis", fr.target_pelvis.data());
  if (!object_names_.empty()) f.append("/frames/object_poses", poses.data());
  if (!tool_names_.empty()) append_tool_frames(fr.tools, at);
  append_contact_frames(f, contacts_, fr.contacts, at);
  ++frames_;
}

void ResultWriter::append_tool_frames(const std::vector<ToolFrame>& tools, const std::string& at) {
  const size_t T = tools.size();
  std::vector<double> poses(7 * T), closure(T), force(3 * T), torque(3 * T);
  for (size_t t = 0; t < T; ++t) {
    const ToolFrame& tf = tools[t];
    const std::string what = at + ": tool '" + tool_names_[t] + "'";
    pose_to_row(tf.pose, &poses[7 * t], what + ": its pose");
    require(std::isfinite(tf.closure) && tf.force.allFinite() && tf.torque.allFinite(), what,
            ": closure, force or torque holds a non-finite value; not written");
    closure[t] = tf.closure;
    std::copy(tf.force.data(), tf.force.data() + 3, &force[3 * t]);
    std::copy(tf.torque.data(), tf.torque.data() + 3, &torque[3 * t]);
  }
  file_->append("/frames/tool_poses", poses.data());
  file_->append("/frames/tool_closure", closure.data());
  file_->append("/frames/tool_force", force.data());
  file_->append("/frames/tool_torque", torque.data());
}

void ResultWriter::write_tool_events(const std::vector<ToolEvent>& events) {
  if (events.empty()) return;
  const std::int64_t E = std::int64_t(events.size());
  std::vector<double> time;
  std::vector<int> points;
  std::vector<std::string> tool, body, kind;
  for (const ToolEvent& e : events) {
    require(e.kind == "grasp" || e.kind == "release", file_->path(), ": tool event kind '", e.kind,
            "', expected grasp or release");
    time.push_back(e.time);
    points.push_back(e.points);
    tool.push_back(e.tool);
    body.push_back(e.body);
    kind.push_back(e.kind);
  }
  file_->write_nd("/tool_events/time", time.data(), {E});
  file_->write_nd("/tool_events/points", points.data(), {E});
  file_->write_strings("/tool_events/tool", tool);
  file_->write_strings("/tool_events/body", body);
  file_->write_strings("/tool_events/kind", kind);
}

void ResultWriter::write_bones(const SimulationResult& r) {
  if (r.step_bones.empty() && r.start_bones.empty()) return;
  const std::string& path = file_->path();
  const std::int64_t S = r.step_time.size(), J = num_joints_;
  require(std::int64_t(r.step_bones.size()) == S && r.start_bones.size() == 2, path, ": ", r.step_bones.size(),
          " steps of bones for ", S, " steps and ", r.start_bones.size(), " start poses (expected 2)");
  auto rows = [&](const std::vector<std::vector<Isometry>>& seq, const std::string& name) {
    std::vector<double> out(seq.size() * size_t(J) * 7);
    for (size_t s = 0; s < seq.size(); ++s) {
      require(std::int64_t(seq[s].size()) == J, path, ": ", name, " entry ", s, " has ", seq[s].size(),
              " bones, expected ", J, " (24 per body)");
      for (std::int64_t j = 0; j < J; ++j)
        pose_to_row(seq[s][size_t(j)], &out[(s * size_t(J) + size_t(j)) * 7],
                    path + ": " + name + " entry " + std::to_string(s) + ", bone " + std::to_string(j));
    }
    return out;
  };
  file_->write_nd("/steps/bones", rows(r.step_bones, "/steps/bones").data(), {S, J, 7});
  file_->write_nd("/meta/start_bones", rows(r.start_bones, "/meta/start_bones").data(), {2, J, 7});
}

void ResultWriter::finish(const SimulationResult& r) {
  auto& f = *file_;
  f.write_scalar("/meta/format_version", std::int64_t(kResultFormatVersion));
  f.write_string("/meta/units", "metres, seconds");
  f.write_string("/meta/avatar", r.avatar);
  f.write_string("/meta/motion", r.motion);
  f.write_scalar("/meta/dt", r.dt);
  f.write_string("/meta/bones", r.bones_dynamic ? "dynamic" : "kinematic");
  f.write_scalar("/meta/newton_iters", std::int64_t(r.newton_iters));
  f.write_scalar("/meta/incomplete", std::int64_t(r.incomplete ? 1 : 0));
  if (r.incomplete) f.write_string("/meta/stop_reason", r.stop_reason);
  const std::int64_t S = r.step_time.size();
  f.write_nd("/steps/time", r.step_time.data(), {S});
  f.write_nd("/steps/energy", r.step_energy.data(), {S});
  f.write_nd("/steps/grad_norm", r.step_grad_norm.data(), {S});
  f.write_nd("/steps/newton_decrement", r.step_decrement.data(), {S});
  f.write_nd("/steps/outcome", r.step_outcome.data(), {S});
  f.write_nd("/steps/ms", r.step_ms.data(), {S});
  write_bones(r);
  write_tool_events(r.tool_events);
  f.commit();
}

void write_simulation_result(const SimulationResult& r, const std::string& path) {
  const int nr = r.frame_reduced.empty() ? 0 : int(r.frame_reduced[0].size());
  require(r.frame_target_pelvis.empty() || r.frame_target_pelvis.size() == r.frame_time.size(), path, ": ",
          r.frame_target_pelvis.size(), " target pelvis positions for ", r.frame_time.size(), " frames");
  for (const ObjectTrack& t : r.objects)
    require(t.poses.size() == r.frame_time.size(), path, ": object '", t.name, "' has ", t.poses.size(),
            " poses for ", r.frame_time.size(), " frames");
  for (const ToolTrack& t : r.tools)
    require(t.frames.size() == r.frame_time.size(), path, ": tool '", t.name, "' has ", t.frames.size(),
            " frames for ", r.frame_time.size(), " frames");
  for (const ContactTrack& c : r.contacts)
    require(c.frames.size() == r.frame_time.size(), path, ": contact '", c.term, "' on '", c.body, "' has ",
            c.frames.size(), " frames for ", r.frame_time.size(), " frames");
  ResultWriter w(path, r.faces, r.surface_rest, nr, !r.frame_target_pelvis.empty(), result_scene(r));
  for (size_t i = 0; i < r.frame_time.size(); ++i) {
    FrameData fr;
    fr.time = r.frame_time[i];
    fr.step_ms = r.frame_step_ms[i];
    fr.positions = r.frame_positions[i];
    fr.displacement = r.frame_displacement[i];
    fr.joints = r.frame_joints[i];
    fr.reduced = r.frame_reduced[i];
    if (!r.frame_target_pelvis.empty()) fr.target_pelvis = r.frame_target_pelvis[i];
    for (const ObjectTrack& t : r.objects) fr.object_poses.push_back(t.poses[i]);
    for (const ToolTrack& t : r.tools) fr.tools.push_back(t.frames[i]);
    for (const ContactTrack& c : r.contacts) fr.contacts.push_back(c.frames[i]);
    w.add_frame(fr);
  }
  w.finish(r);
}

}  // namespace sflsh
