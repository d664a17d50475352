#include "sflsh/scene/simulation_run.hpp"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>

#include "sflsh/core/error.hpp"
#include "sflsh/core/interrupt.hpp"
#include "sflsh/core/percentile.hpp"
#include "sflsh/core/progress.hpp"
#include "sflsh/io/hdf5_file.hpp"
#include "sflsh/sim/skeleton_pose.hpp"

namespace sflsh {
namespace {

bool finite_state(const Configuration& q) {
  if (!q.z.allFinite()) return false;
  for (const auto& b : q.bones)
    if (!b.matrix().allFinite()) return false;
  return true;
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

// World position of SMPL joint 0 (the pelvis) under bone transforms `bones`:
// G_0 J̄_0, as joint_world_positions() and the result's /frames/joints put it.
Vec3 pelvis_position(const Avatar& avatar, const std::vector<Isometry>& bones) {
  return bones[0] * Vec3(avatar.joints_rest.row(0).transpose());
}

}  // namespace

double SimulationResult::median_step_ms() const { return percentile(step_ms, 0.5); }
double SimulationResult::p95_step_ms() const { return percentile(step_ms, 0.95); }

std::string SimulationResult::describe() const {
  std::ostringstream o;
  o << std::fixed << std::setprecision(3);
  o << "simulated " << (step_time.empty() ? 0.0 : step_time.back()) << " s of " << motion << " on " << avatar << ": "
    << step_time.size() << " steps of " << dt * 1e3 << " ms (bones " << (bones_dynamic ? "dynamic" : "kinematic")
    << ", " << newton_iters << " Newton iteration(s) per step), " << num_frames << " frames\n"
    << "steps: " << accepted << " accepted, " << damped << " damped, " << rejected << " rejected; step time median "
    << median_step_ms() << " ms, p95 " << p95_step_ms() << " ms\n";
  if (!part_names.empty() && !step_ms.empty()) {
    o << "mean ms per step:";
    for (size_t i = 0; i < part_names.size(); ++i)
      o << (i ? ", " : " ") << part_names[i] << " " << part_ms[i] / double(step_ms.size());
    o << "\n";
  }
  if (pelvis_frames > 0)
    o << std::setprecision(1) << "pelvis vs motion root: mean " << pelvis_error_mean * 1e3 << " mm, max "
      << pelvis_error_max * 1e3 << " mm over " << pelvis_frames << " frames\n";
  return o.str();
}

std::vector<Isometry> target_bones(const Avatar& avatar, const BodyPose& pose) {
  return bone_transforms_from_pose(avatar.joints_rest, avatar.parents, pose);
}

SimulationResult run_simulation(std::shared_ptr<const Avatar> avatar, const MotionClip& motion, const RunOptions& options,
                                const std::function<void(const FrameData&)>& on_frame) {
  require(motion.num_frames() > 0, motion.name, ": motion has no frames");
  const double h = options.sim.h;
  require(h > 0 && std::isfinite(h), "time step must be positive, got ", h);
  require(options.output_fps > 0, "--output-fps must be positive, got ", options.output_fps);
  const double seconds = options.seconds > 0 ? options.seconds : motion.duration();
  require(seconds > 0, motion.name, ": motion lasts 0 s; give a duration");
  const long steps = std::max(1L, long(std::llround(seconds / h)));

  Simulator sim(avatar, options.sim);
  if (options.sim.bones_dynamic) {
    std::vector<EnergyTermPtr> terms;
    add_skeleton_terms(terms, *avatar, options.skeleton);
    for (auto& t : terms) sim.add_term(std::move(t));
  }
  std::vector<Isometry> targets = target_bones(*avatar, motion.sample(0.0));
  if (options.start_at_rest) {
    sim.reset(targets);
  } else {
    // Start moving with the motion: q_{-1} = Δ⁻¹ q_0 with Δ = G(h) G(0)⁻¹ the
    // first step's motion of each bone, so (q_0 − q_{-1})/h is the motion's
    // velocity. Mocap clips start mid-motion (a run at 3-4 m/s); from rest
    // the tracking springs needed ~0.3 s and up to 4 cm to catch up.
    const std::vector<Isometry> next = target_bones(*avatar, motion.sample(h));
    Configuration q0, q_prev;
    q0.bones = targets;
    q0.z = VecX::Zero(avatar->num_reduced());
    q_prev.z = q0.z;
    for (size_t j = 0; j < targets.size(); ++j) q_prev.bones.push_back(targets[j] * next[j].inverse() * targets[j]);
    sim.reset(q0, q_prev);
  }

  SimulationResult r;
  r.motion = motion.name;
  r.dt = h;
  r.bones_dynamic = options.sim.bones_dynamic;
  r.newton_iters = options.sim.newton.iterations;
  r.faces = avatar->surface_faces;
  r.surface_rest = avatar->surface_rest;
  double pelvis_error_sum = 0;
  // `targets` holds the target bones at time t.
  auto record_frame = [&](double t, double ms) {
    FrameData fr{t, ms, sim.posed_surface(), sim.soft_displacement(), sim.joints(), sim.state().z,
                 pelvis_position(*avatar, targets)};
    const double pelvis_error = (fr.joints.row(0).transpose() - fr.target_pelvis).norm();
    pelvis_error_sum += pelvis_error;
    r.pelvis_error_max = std::max(r.pelvis_error_max, pelvis_error);
    ++r.pelvis_frames;
    r.pelvis_error_mean = pelvis_error_sum / r.pelvis_frames;
    ++r.num_frames;
    if (on_frame) on_frame(fr);
    if (!options.keep_frames) return;
    r.frame_time.push_back(t);
    r.frame_step_ms.push_back(ms);
    r.frame_positions.push_back(std::move(fr.positions));
    r.frame_displacement.push_back(std::move(fr.displacement));
    r.frame_joints.push_back(std::move(fr.joints));
    r.frame_reduced.push_back(std::move(fr.reduced));
    r.frame_target_pelvis.push_back(fr.target_pelvis);
  };
  record_frame(0.0, 0.0);

  const double frame_dt = 1.0 / options.output_fps;
  double next_frame = frame_dt, ms_since_frame = 0;
  int steps_since_frame = 0;
  Progress progress("simulating " + motion.name, steps);
  for (long s = 0; s < steps; ++s) {
    if (interrupt_signal()) throw_if_interrupted("at step " + std::to_string(s + 1) + " of " + std::to_string(steps));
    const double t = (s + 1) * h;
    const BodyPose pose = motion.sample(t);
    targets = target_bones(*avatar, pose);
    const StepReport rep = sim.step(targets, pose);
    if (!finite_state(sim.state()) || !std::isfinite(rep.energy_after))
      fail(motion.name, ": simulation state became non-finite at step ", s + 1, " (t = ", t, " s); try a smaller --dt");
    r.step_time.push_back(t);
    r.step_energy.push_back(rep.energy_after);
    r.step_grad_norm.push_back(rep.grad_norm_before);
    r.step_decrement.push_back(rep.newton_decrement);
    r.step_outcome.push_back(int(rep.outcome));
    r.step_ms.push_back(rep.ms_total);
    if (r.part_names.empty()) {
      for (const TermEnergy& e : rep.energies) r.part_names.push_back(e.name);
      r.part_names.push_back("solve");
      r.part_ms.assign(r.part_names.size(), 0.0);
    }
    for (size_t i = 0; i < rep.energies.size() && i + 1 < r.part_ms.size(); ++i) r.part_ms[i] += rep.energies[i].ms;
    r.part_ms.back() += rep.ms_solve;
    r.accepted += rep.accepted;
    r.damped += rep.damped;
    r.rejected += rep.rejected;
    ms_since_frame += rep.ms_total;
    ++steps_since_frame;
    if (options.on_step) options.on_step(sim, rep);
    if (t + 1e-9 >= next_frame) {
      record_frame(t, ms_since_frame / steps_since_frame);
      next_frame += frame_dt;
      ms_since_frame = 0;
      steps_since_frame = 0;
    }
    if (options.progress) progress.update(s + 1);
  }
  if (options.progress) progress.finish();
  return r;
}

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
