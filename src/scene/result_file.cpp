#include "sflsh/scene/result_file.hpp"

#include <algorithm>
#include <cmath>

#include "sflsh/core/error.hpp"

namespace sflsh {
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

}  // namespace

ResultWriter::ResultWriter(const std::string& path, const Triangles& faces, const Points& surface_rest,
                           int num_reduced, bool target_pelvis)
    : file_(std::make_unique<io::Hdf5File>(path, io::Hdf5File::Mode::Write)), target_pelvis_(target_pelvis) {
  auto& f = *file_;
  f.write_matrix("/surface/faces", faces);
  f.write_matrix("/surface/rest", surface_rest);
  const std::int64_t V = surface_rest.rows();
  f.create_appendable("/frames/time", {});
  f.create_appendable("/frames/step_ms", {});
  f.create_appendable("/frames/positions", {V, 3}, true);
  f.create_appendable("/frames/displacement", {V, 3}, true);
  f.create_appendable("/frames/joints", {24, 3});
  f.create_appendable("/frames/reduced", {num_reduced});
  if (target_pelvis_) f.create_appendable("/frames/target_pelvis", {3});
}

ResultWriter::~ResultWriter() = default;

void ResultWriter::add_frame(const FrameData& fr) {
  auto& f = *file_;
  f.append("/frames/time", &fr.time);
  f.append("/frames/step_ms", &fr.step_ms);
  f.append("/frames/positions", fr.positions.data());
  f.append("/frames/displacement", fr.displacement.data());
  f.append("/frames/joints", fr.joints.data());
  f.append("/frames/reduced", fr.reduced.data());
  if (target_pelvis_) f.append("/frames/target_pelvis", fr.target_pelvis.data());
  ++frames_;
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
  const std::int64_t S = r.step_time.size();
  f.write_nd("/steps/time", r.step_time.data(), {S});
  f.write_nd("/steps/energy", r.step_energy.data(), {S});
  f.write_nd("/steps/grad_norm", r.step_grad_norm.data(), {S});
  f.write_nd("/steps/newton_decrement", r.step_decrement.data(), {S});
  f.write_nd("/steps/outcome", r.step_outcome.data(), {S});
  f.write_nd("/steps/ms", r.step_ms.data(), {S});
  f.commit();
}

void write_simulation_result(const SimulationResult& r, const std::string& path) {
  const int nr = r.frame_reduced.empty() ? 0 : int(r.frame_reduced[0].size());
  require(r.frame_target_pelvis.empty() || r.frame_target_pelvis.size() == r.frame_time.size(), path, ": ",
          r.frame_target_pelvis.size(), " target pelvis positions for ", r.frame_time.size(), " frames");
  ResultWriter w(path, r.faces, r.surface_rest, nr, !r.frame_target_pelvis.empty());
  for (size_t i = 0; i < r.frame_time.size(); ++i)
    w.add_frame({r.frame_time[i], r.frame_step_ms[i], r.frame_positions[i], r.frame_displacement[i], r.frame_joints[i],
                 r.frame_reduced[i], r.frame_target_pelvis.empty() ? Vec3(Vec3::Zero()) : r.frame_target_pelvis[i]});
  w.finish(r);
}

SimulationResult read_simulation_result(const std::string& path) {
  io::Hdf5File f(path, io::Hdf5File::Mode::Read);
  require(f.has("/meta/format_version"), path, ": not an sflsh result file (dataset /meta/format_version is missing)");
  const double v = f.read_scalar("/meta/format_version");
  require(v == kResultFormatVersion, path, ": dataset /meta/format_version is ", v, ", expected ", kResultFormatVersion);
  SimulationResult r;
  r.avatar = f.read_string("/meta/avatar");
  r.motion = f.read_string("/meta/motion");
  r.dt = f.read_scalar("/meta/dt");
  r.bones_dynamic = f.read_string("/meta/bones") == "dynamic";
  r.newton_iters = int(f.read_scalar("/meta/newton_iters"));
  r.faces = f.read_int_matrix("/surface/faces", -1, 3);
  r.surface_rest = f.read_matrix("/surface/rest", -1, 3);
  const std::int64_t V = r.surface_rest.rows();
  MatXr t = f.read_matrix("/frames/time");
  const std::int64_t F = t.rows();
  r.frame_time.assign(t.data(), t.data() + F);
  r.num_frames = int(F);
  std::vector<std::int64_t> shape;
  r.frame_positions = unstack(f.read_nd("/frames/positions", {F, V, 3}, &shape), shape);
  r.frame_displacement = unstack(f.read_nd("/frames/displacement", {F, V, 3}, &shape), shape);
  r.frame_joints = unstack(f.read_nd("/frames/joints", {F, 24, 3}, &shape), shape);
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
  std::vector<double> outcome;
  vec("/steps/outcome", outcome);
  for (double o : outcome) {
    r.step_outcome.push_back(int(o));
    (o == 0 ? r.accepted : o == 1 ? r.damped : r.rejected)++;
  }
  return r;
}

}  // namespace sflsh
