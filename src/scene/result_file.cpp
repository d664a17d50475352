#include "sflsh/scene/result_file.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "sflsh/core/error.hpp"
#include "sflsh/io/crash_isolation.hpp"
#include "sflsh/scene/result_contacts.hpp"

namespace sflsh {
namespace {

constexpr const char* kShapes[] = {"plane", "sphere", "box", "capsule", "cylinder", "mesh"};
constexpr const char* kKinds[] = {"static", "kinematic", "dynamic"};
/// Largest |‖q‖ − 1| a stored quaternion may have (they are written normalized in float64).
constexpr double kUnitTolerance = 1e-6;

template <size_t N>
bool one_of(const std::string& s, const char* const (&list)[N]) {
  return std::find(std::begin(list), std::end(list), s) != std::end(list);
}

template <size_t N>
std::string joined(const char* const (&list)[N]) {
  std::string out;
  for (const char* x : list) out += (out.empty() ? "" : ", ") + std::string(x);
  return out;
}

std::string object_group(size_t o) { return "/objects/" + std::to_string(o); }
std::string tool_group(size_t t) { return "/tools/" + std::to_string(t); }

/// Checks that `scene` fits a skin of V vertices; `where` starts every message
/// (the file path). The writer and the reader share it.
void check_scene(const ResultScene& scene, Eigen::Index V, const std::string& where) {
  const auto& names = scene.body_names;
  const auto& off = scene.body_vertex_offsets;
  require(!names.empty() || off.empty(), where, ": /bodies/vertex_offsets given without /bodies/names");
  if (!names.empty()) {
    require(off.size() == names.size() + 1, where, ": /bodies/names has ", names.size(), " bodies, so /bodies/vertex_offsets needs ",
            names.size() + 1, " entries, got ", off.size());
    require(off.front() == 0 && off.back() == V, where, ": /bodies/vertex_offsets must start at 0 and end at the ", V,
            " skin vertices, got ", off.front(), " ... ", off.back());
    for (size_t b = 0; b + 1 < off.size(); ++b)
      require(off[b] <= off[b + 1], where, ": /bodies/vertex_offsets must not decrease (entry ", b + 1, ")");
  }
  for (size_t o = 0; o < scene.objects.size(); ++o) {
    const ObjectTrack& t = scene.objects[o];
    const std::string at = where + ": " + object_group(o) + " ('" + t.name + "')";
    require(one_of(t.shape, kShapes), at, ": shape '", t.shape, "' is not one of ", joined(kShapes));
    require(one_of(t.kind, kKinds), at, ": kind '", t.kind, "' is not one of ", joined(kKinds));
    require(t.vertices.rows() > 0 && t.faces.rows() > 0, at, ": needs a surface (", t.vertices.rows(), " vertices, ",
            t.faces.rows(), " faces)");
    require(t.vertices.allFinite(), at, ": vertices contain NaN or Inf");
    require(t.faces.minCoeff() >= 0 && t.faces.maxCoeff() < t.vertices.rows(), at, ": face indices must lie in [0, ",
            t.vertices.rows(), ")");
  }
}

/// Pose as 7 numbers: position (m), then the unit quaternion w x y z (w >= 0).
void pose_to_row(const Isometry& T, double* out, const std::string& what) {
  const Mat3 R = T.linear();
  require(T.translation().allFinite() && R.allFinite(), what, " is not finite");
  require((R.transpose() * R - Mat3::Identity()).norm() < kUnitTolerance && R.determinant() > 0, what,
          " is not a rigid motion (its linear part is not a rotation)");
  Eigen::Quaterniond q(R);
  q.normalize();
  if (q.w() < 0) q.coeffs() *= -1.0;
  const Vec3 p = T.translation();
  const double row[7] = {p.x(), p.y(), p.z(), q.w(), q.x(), q.y(), q.z()};
  std::copy(row, row + 7, out);
}

Isometry pose_from_row(const double* in, const std::string& what) {
  require(std::all_of(in, in + 7, [](double v) { return std::isfinite(v); }), what, ": the pose is not finite");
  Eigen::Quaterniond q(in[3], in[4], in[5], in[6]);
  require(std::abs(q.norm() - 1.0) < kUnitTolerance, what, ": quaternion (w x y z) has norm ", q.norm(),
          ", expected a unit quaternion");
  Isometry T = Isometry::Identity();
  T.linear() = q.normalized().toRotationMatrix();
  T.translation() = Vec3(in[0], in[1], in[2]);
  return T;
}

std::vector<Points> unstack(const std::vector<double>& flat, const std::vector<std::int64_t>& shape) {
  std::vector<Points> out(shape[0]);
  const std::int64_t n = shape[1] * 3;
  for (std::int64_t f = 0; f < shape[0]; ++f) {
    out[f].resize(shape[1], 3);
    std::copy(flat.begin() + f * n, flat.begin() + (f + 1) * n, out[f].data());
  }
  return out;
}

}  // namespace

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

namespace {

/// Reads /tools, /frames/tool_* (F frames) and /tool_events into `r`, when the file has them.
void read_tools(const io::Hdf5File& f, const std::string& path, std::int64_t F, SimulationResult& r) {
  std::int64_t T = 0;
  while (f.has(tool_group(size_t(T)))) ++T;
  if (T > 0) {
    const std::vector<double> poses = f.read_nd("/frames/tool_poses", {F, T, 7});
    const std::vector<double> closure = f.read_nd("/frames/tool_closure", {F, T});
    const std::vector<double> force = f.read_nd("/frames/tool_force", {F, T, 3});
    const std::vector<double> torque = f.read_nd("/frames/tool_torque", {F, T, 3});
    for (std::int64_t t = 0; t < T; ++t) {
      ToolTrack track{f.read_string(tool_group(size_t(t)) + "/name"), {}};
      for (std::int64_t i = 0; i < F; ++i) {
        const size_t k = size_t(i * T + t);
        ToolFrame tf;
        tf.pose = pose_from_row(&poses[7 * k], path + ": dataset /frames/tool_poses, frame " + std::to_string(i) +
                                                   ", tool " + std::to_string(t));
        tf.closure = closure[k];
        tf.force = Vec3(force[3 * k], force[3 * k + 1], force[3 * k + 2]);
        tf.torque = Vec3(torque[3 * k], torque[3 * k + 1], torque[3 * k + 2]);
        track.frames.push_back(tf);
      }
      r.tools.push_back(std::move(track));
    }
  } else {
    require(!f.has("/frames/tool_poses"), path, ": dataset /frames/tool_poses given without /tools");
  }
  if (!f.has("/tool_events/time")) return;
  const MatXr time = f.read_matrix("/tool_events/time", -1, 1);
  const std::int64_t E = time.rows();
  const auto points = f.read_int_matrix("/tool_events/points", E, 1);
  const std::vector<std::string> tool = f.read_strings("/tool_events/tool"), body = f.read_strings("/tool_events/body"),
                                 kind = f.read_strings("/tool_events/kind");
  require(std::int64_t(tool.size()) == E && std::int64_t(body.size()) == E && std::int64_t(kind.size()) == E, path,
          ": the /tool_events datasets differ in length (", E, " times)");
  for (std::int64_t e = 0; e < E; ++e)
    r.tool_events.push_back({time(e, 0), tool[size_t(e)], body[size_t(e)], kind[size_t(e)], points(e, 0)});
}

}  // namespace

std::vector<std::vector<Isometry>> read_result_poses(const io::Hdf5File& f, const std::string& path,
                                                     const std::string& name, std::int64_t entries,
                                                     std::int64_t bones) {
  const std::vector<double> rows = f.read_nd(name, {entries, bones, 7});
  std::vector<std::vector<Isometry>> out(static_cast<size_t>(entries));
  for (std::int64_t s = 0; s < entries; ++s)
    for (std::int64_t j = 0; j < bones; ++j)
      out[size_t(s)].push_back(pose_from_row(&rows[size_t((s * bones + j) * 7)], path + ": dataset " + name +
                                                                                   ", entry " + std::to_string(s) +
                                                                                   ", bone " + std::to_string(j)));
  return out;
}

static SimulationResult read_simulation_result_in_this_process(const std::string& path) {
  io::Hdf5File f(path, io::Hdf5File::Mode::Read);
  require(f.has("/meta/format_version"), path, ": not an sflsh result file (dataset /meta/format_version is missing)");
  const double v = f.read_scalar("/meta/format_version");
  require(v == 1 || v == kResultFormatVersion, path, ": dataset /meta/format_version is ", v, ", expected 1 to ",
          kResultFormatVersion);
  SimulationResult r;
  r.avatar = f.read_string("/meta/avatar");
  r.motion = f.read_string("/meta/motion");
  r.dt = f.read_scalar("/meta/dt");
  r.bones_dynamic = f.read_string("/meta/bones") == "dynamic";
  r.newton_iters = f.read_int_scalar("/meta/newton_iters", 0, 1000000);
  if (f.has("/meta/incomplete")) {  // absent in files written before it existed: complete
    const double inc = f.read_scalar("/meta/incomplete");
    require(inc == 0 || inc == 1, path, ": dataset /meta/incomplete is ", inc, ", expected 0 or 1");
    r.incomplete = inc == 1;
    if (r.incomplete && f.has("/meta/stop_reason")) r.stop_reason = f.read_string("/meta/stop_reason");
  }
  r.faces = f.read_int_matrix("/surface/faces", -1, 3);
  r.surface_rest = f.read_matrix("/surface/rest", -1, 3);
  const std::int64_t V = r.surface_rest.rows();
  require(r.faces.rows() == 0 || (r.faces.minCoeff() >= 0 && r.faces.maxCoeff() < V), path,
          ": dataset /surface/faces has indices outside [0, ", V, ")");
  ResultScene scene;
  if (f.has("/bodies/names")) {
    scene.body_names = f.read_strings("/bodies/names");
    const auto off = f.read_int_matrix("/bodies/vertex_offsets", -1, 1);
    scene.body_vertex_offsets.assign(off.data(), off.data() + off.size());
  } else {
    require(!f.has("/bodies/vertex_offsets"), path, ": dataset /bodies/vertex_offsets given without /bodies/names");
  }
  std::int64_t O = 0;
  if (f.has("/frames/object_poses")) {
    const auto s = f.shape("/frames/object_poses");
    require(s.size() == 3, path, ": dataset /frames/object_poses must have shape (frames, objects, 7)");
    O = s[1];
  }
  for (std::int64_t o = 0; o < O; ++o) {
    const std::string g = object_group(size_t(o));
    require(f.has(g), path, ": /frames/object_poses holds ", O, " objects but group ", g, " is missing");
    ObjectTrack t;
    t.name = f.read_string(g + "/name");
    t.shape = f.read_string(g + "/shape");
    t.kind = f.read_string(g + "/kind");
    t.vertices = f.read_matrix(g + "/vertices", -1, 3);
    t.faces = f.read_int_matrix(g + "/faces", -1, 3);
    scene.objects.push_back(std::move(t));
  }
  require(!f.has(object_group(size_t(O))), path, ": group ", object_group(size_t(O)), " has no poses in /frames/object_poses (",
          O, " objects)");
  check_scene(scene, V, path);
  r.body_names = std::move(scene.body_names);
  r.body_vertex_offsets = std::move(scene.body_vertex_offsets);
  r.objects = std::move(scene.objects);
  MatXr t = f.read_matrix("/frames/time");
  const std::int64_t F = t.rows();
  r.frame_time.assign(t.data(), t.data() + F);
  r.num_frames = int(F);
  std::vector<std::int64_t> shape;
  r.frame_positions = unstack(f.read_nd("/frames/positions", {F, V, 3}, &shape), shape);
  r.frame_displacement = unstack(f.read_nd("/frames/displacement", {F, V, 3}, &shape), shape);
  r.frame_joints = unstack(f.read_nd("/frames/joints", {F, 24 * std::int64_t(num_bodies(r)), 3}, &shape), shape);
  if (O > 0) {
    const std::vector<double> poses = f.read_nd("/frames/object_poses", {F, O, 7});
    for (std::int64_t o = 0; o < O; ++o)
      for (std::int64_t i = 0; i < F; ++i)
        r.objects[size_t(o)].poses.push_back(pose_from_row(
            &poses[size_t((i * O + o) * 7)], path + ": dataset /frames/object_poses, frame " + std::to_string(i) +
                                                 ", object " + std::to_string(o)));
  }
  read_tools(f, path, F, r);
  r.contacts = read_contacts(f, F);  // absent in files written before contacts were stored
  MatXr red = f.read_matrix("/frames/reduced", F, -1);
  for (std::int64_t i = 0; i < F; ++i) r.frame_reduced.push_back(red.row(i).transpose());
  MatXr ms = f.read_matrix("/frames/step_ms", F, 1);
  r.frame_step_ms.assign(ms.data(), ms.data() + F);
  if (f.has("/frames/target_pelvis")) {  // absent in files written before it existed
    const MatXr tp = f.read_matrix("/frames/target_pelvis", F, 3);
    double sum = 0;
    for (std::int64_t i = 0; i < F; ++i) {
      r.frame_target_pelvis.push_back(tp.row(i).transpose());
      const double e = (r.frame_joints[i].row(0).transpose() - r.frame_target_pelvis.back()).norm();
      sum += e;
      r.pelvis_error_max = std::max(r.pelvis_error_max, e);
    }
    r.pelvis_frames = int(F);
    r.pelvis_error_mean = F > 0 ? sum / double(F) : 0.0;
  }
  auto vec = [&](const std::string& name, std::vector<double>& out) {
    MatXr m = f.read_matrix(name, -1, 1);
    out.assign(m.data(), m.data() + m.rows());
  };
  vec("/steps/time", r.step_time);
  vec("/steps/energy", r.step_energy);
  vec("/steps/grad_norm", r.step_grad_norm);
  vec("/steps/newton_decrement", r.step_decrement);
  vec("/steps/ms", r.step_ms);
  if (f.has("/steps/bones") || f.has("/meta/start_bones")) {  // absent in files written before they existed
    const std::int64_t J = 24 * std::int64_t(num_bodies(r));
    r.step_bones = read_result_poses(f, path, "/steps/bones", std::int64_t(r.step_time.size()), J);
    r.start_bones = read_result_poses(f, path, "/meta/start_bones", 2, J);
  }
  std::vector<double> outcome;
  vec("/steps/outcome", outcome);
  for (double o : outcome) {
    r.step_outcome.push_back(int(o));
    (o == 0 ? r.accepted : o == 1 ? r.damped : r.rejected)++;
  }
  return r;
}

SimulationResult read_simulation_result(const std::string& path) {
  // A file on which libhdf5 itself crashes is refused, not read (io/crash_isolation.hpp).
  return io::read_in_child_first(path, [&] { return read_simulation_result_in_this_process(path); });
}

}  // namespace sflsh
