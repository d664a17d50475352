// Reading a result file (result_file.hpp): every dataset checked against
// the others, in a child process (crash_isolation.hpp) so that a corrupt file
// cannot take the reader down.
#include <algorithm>
#include <cmath>

#include "scene/result_file_format.hpp"
#include "sflsh/core/error.hpp"
#include "sflsh/io/crash_isolation.hpp"
#include "sflsh/scene/result_contacts.hpp"
#include "sflsh/scene/result_file.hpp"

namespace sflsh {

using result_file_detail::check_scene;
using result_file_detail::object_group;
using result_file_detail::pose_from_row;
using result_file_detail::tool_group;

namespace {

std::vector<Points> unstack(const std::vector<double>& flat, const std::vector<std::int64_t>& shape) {
  std::vector<Points> out(shape[0]);
  const std::int64_t n = shape[1] * 3;
  for (std::int64_t f = 0; f < shape[0]; ++f) {
    out[f].resize(shape[1], 3);
    std::copy(flat.begin() + f * n, flat.begin() + (f + 1) * n, out[f].data());
  }
  return out;
}


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
