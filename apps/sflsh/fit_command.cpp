// `sflsh fit`: per-region material parameters from observed skin motion
// (Ceres).
#include <cmath>
#include <filesystem>
#include <iostream>

#include <yaml-cpp/yaml.h>

#include "command.hpp"
#include "sflsh/asset/avatar_file.hpp"
#include "sflsh/core/error.hpp"
#include "sflsh/core/time_step.hpp"
#include "sflsh/fit/material_fit.hpp"
#include "sflsh/fit/motion_bones.hpp"
#include "sflsh/fit/observations.hpp"
#include "sflsh/fit/reference_observations.hpp"
#include "sflsh/fit/shape_map.hpp"
#include "sflsh/io/atomic_output.hpp"
#include "sflsh/motion/load_motion.hpp"
#include "sflsh/scene/material_file.hpp"
#include "sflsh/scene/yaml_document.hpp"

namespace sflsh::cli {
namespace {

struct FitArgs {
  std::string avatar, observed, motion, params = "young,fung_c", regions = "all", out, plot, material, dt, loss = "none";
  std::string write_reference, dataset, map;
  double damping = 0, fps = 30, noise = 0, loss_scale = 0.003, seconds = 2, regularization = 1e-4;
  bool leave_one_out = false;
  int vertex_stride = 1, frame_stride = 1, max_iterations = 30;
  unsigned seed = 1;
  bool numeric = false, start_at_rest = false;
};

/// `--write-reference`: full-FEM observations of --motion on --avatar (with --material).
void run_reference(const FitArgs& a) {
  require(!a.motion.empty(), "fit --write-reference: give --motion");
  require(std::isfinite(a.seconds) && a.seconds > 0, "--seconds must be > 0, got ", a.seconds);
  io::check_output_file(a.write_reference, "--write-reference");
  auto avatar = std::make_shared<Avatar>(read_avatar(a.avatar));
  if (!a.material.empty()) apply_material_file(a.material, avatar->materials);
  const double h = a.dt.empty() ? 1.0 / 60.0 : parse_time_step(a.dt);
  MotionOptions mo;
  mo.rest_joints = avatar->joints_rest;
  mo.builtin_seconds = a.seconds;
  const MotionClip motion = load_motion(a.motion, mo);
  write_reference_observations(avatar, motion, a.motion, a.seconds, h, a.fps, a.write_reference);
  std::cout << "wrote " << a.write_reference << " (full-FEM reference, " << a.seconds << " s of " << a.motion
            << " from rest; fit it with --start-at-rest)\n";
}

/// One subject: the avatar (with --material), its observations (with --noise),
/// the steps they fall on and the bones to prescribe: the observed run's own when
/// the file holds them (a run with dynamic bones), else those of its motion.
struct LoadedSubject {
  std::shared_ptr<Avatar> avatar;
  Observations obs;
  std::vector<int> steps;
  BoneSequence bones;
  std::string motion;
  std::string bones_source;  ///< where `bones` come from, for the log
};

LoadedSubject load_subject(const FitArgs& a, const std::string& avatar_path, const std::string& observed,
                           const std::string& motion_arg, unsigned seed) {
  LoadedSubject s;
  s.avatar = std::make_shared<Avatar>(read_avatar(avatar_path));
  if (!a.material.empty()) apply_material_file(a.material, s.avatar->materials);
  s.obs = read_observations(observed, a.fps);
  check_observation_vertices(s.obs, int(s.avatar->surface_rest.rows()), avatar_path);
  const double h = !a.dt.empty() ? parse_time_step(a.dt) : (s.obs.dt > 0 ? s.obs.dt : 1.0 / 60.0);
  s.steps = observation_steps(s.obs, h);
  s.motion = !motion_arg.empty() ? motion_arg : s.obs.motion;
  if (!s.obs.step_bones.empty()) {
    // The run's own bones (dynamic ones are not the motion's): the fit prescribes what the run did.
    s.bones = observed_bones(s.obs, h, s.steps.back());
    s.bones_source = "the observed run's own (/steps/bones of a run with " + s.obs.bones + " bones)" +
                     (a.start_at_rest ? "; --start-at-rest is not used (the file holds the run's start)" : "");
  } else {
    if (s.obs.bones == "dynamic")
      std::cerr << "sflsh: warning: " << observed << " was simulated with dynamic bones but holds no /steps/bones; "
                << "fit prescribes the motion's bones\n";
    require(!s.motion.empty(), observed, ": the file names no motion (/meta/motion); give --motion");
    MotionOptions mo;
    mo.rest_joints = s.avatar->joints_rest;
    mo.builtin_seconds = std::max(s.steps.back() * h, h);
    const MotionClip motion = load_motion(s.motion, mo);
    s.bones = motion_bones(*s.avatar, motion, h, s.steps.back(), a.start_at_rest);
    s.bones_source = "the motion's, prescribed";
  }
  if (a.noise > 0) add_gaussian_noise(s.obs, a.noise, seed);
  return s;
}

MaterialFitOptions fit_options(const FitArgs& a) {
  MaterialFitOptions o;
  o.vertex_stride = a.vertex_stride;
  o.frame_stride = a.frame_stride;
  o.loss = a.loss;
  o.loss_scale = a.loss_scale;
  o.numeric = a.numeric;
  o.max_iterations = a.max_iterations;
  o.damping = a.damping;
  o.log = [](const std::string& line) { std::cout << line << std::endl; };
  return o;
}

/// `--dataset fits.yaml`: subjects: [{avatar: A.h5, observed: obs.h5, motion: M (optional)}, ...] -> map.yaml.
void run_dataset(const FitArgs& a) {
  require(!a.out.empty(), "fit --dataset: give --out (the map file)");
  io::check_output_file(a.out, "--out");
  const YAML::Node root = load_yaml_file(a.dataset, "dataset file");
  require(root.IsMap() && root["subjects"] && root["subjects"].IsSequence(), a.dataset,
          ": expected 'subjects:' with a list of {avatar, observed[, motion]}");
  const std::filesystem::path dir = std::filesystem::path(a.dataset).parent_path();
  auto path_of = [&](const YAML::Node& n, const char* key) {
    require(n[key] && n[key].IsScalar(), yaml_where(a.dataset, n), ": subject needs '", key, "'");
    const std::filesystem::path p(n[key].as<std::string>());
    return (p.is_absolute() ? p : dir / p).string();
  };
  std::vector<FitSubject> subjects;
  unsigned seed = a.seed;
  for (const YAML::Node& n : root["subjects"]) {
    require(n.IsMap(), yaml_where(a.dataset, n), ": each subject is a map {avatar, observed[, motion]}");
    const std::string motion = n["motion"] ? n["motion"].as<std::string>() : a.motion;
    LoadedSubject s = load_subject(a, path_of(n, "avatar"), path_of(n, "observed"), motion, seed++);
    subjects.push_back({path_of(n, "observed"), s.avatar, std::move(s.bones), std::move(s.steps), std::move(s.obs.positions)});
  }
  const FitParameters params(*subjects[0].avatar, a.params, a.regions);
  std::cout << "fitting p(beta) = P0 + sum_k beta_k P_k for " << params.size() << " parameters to " << subjects.size()
            << " subjects (regularization " << a.regularization << ")\n";
  const ShapeMapResult r = fit_shape_map(subjects, params, fit_options(a), a.regularization, a.leave_one_out);
  std::cout << r.brief_report << "\nCeres stopped: " << r.termination << "\n" << r.describe(subjects);
  write_shape_map(a.out, r.map, {"sflsh fit --dataset " + a.dataset + " --params " + a.params});
  std::cout << "wrote " << a.out << "\n";
}

/// `--map map.yaml --avatar A.h5`: the map at the avatar's betas, as a material file.
void run_map(const FitArgs& a) {
  require(!a.avatar.empty() && !a.out.empty(), "fit --map: give --avatar (the new shape) and --out");
  io::check_output_file(a.out, "--out");
  const ShapeMap map = read_shape_map(a.map);
  const Avatar avatar = read_avatar(a.avatar);
  double damping = a.damping;
  const std::vector<RegionMaterial> m = shape_map_materials(map, avatar, avatar.betas, a.damping, &damping);
  std::vector<std::string> comment = {"sflsh fit --map " + a.map + " --avatar " + a.avatar};
  if (damping != a.damping) comment.push_back("damping from the map: " + std::to_string(damping) + " s (pass --damping)");
  write_material_file(a.out, m, comment);
  std::cout << "wrote " << a.out << " (materials of the map at the betas of " << a.avatar << ")\n";
}

void run_fit(const FitArgs& a) {
  if (!a.write_reference.empty()) return run_reference(a);
  if (!a.dataset.empty()) return run_dataset(a);
  if (!a.map.empty()) return run_map(a);
  require(!a.avatar.empty() && !a.observed.empty() && !a.out.empty(), "fit: give --avatar, --observed and --out");
  io::check_output_file(a.out, "--out");
  const std::string plot =
      a.plot.empty() ? (std::filesystem::path(a.out).replace_extension("").string() + "_error.svg") : a.plot;
  io::check_output_file(plot, "--plot");
  require(std::isfinite(a.damping) && a.damping >= 0, "--damping must be >= 0 s, got ", a.damping);

  const LoadedSubject sub = load_subject(a, a.avatar, a.observed, a.motion, a.seed);
  const Avatar& avatar = *sub.avatar;
  const Observations& obs = sub.obs;
  const std::vector<int>& steps = sub.steps;
  const BoneSequence& bones = sub.bones;
  const std::string& motion_spec = sub.motion;
  const double h = bones.h;
  const FitParameters params(avatar, a.params, a.regions);

  const MaterialFitOptions o = fit_options(a);
  std::cout << "fitting " << params.size() << " parameters (" << a.params << " on " << params.regions().size()
            << " regions) to " << obs.time.size() << " frames of " << a.observed << " (motion " << motion_spec << ", "
            << steps.back() << " steps of " << h * 1e3 << " ms; residuals on every " << a.vertex_stride
            << ". vertex and every " << a.frame_stride << ". frame; " << (a.numeric ? "numeric" : "analytic")
            << " Jacobians; loss " << a.loss << ")\nbones: " << sub.bones_source << "\n";
  const MaterialFitResult r = fit_materials(avatar, params, bones, steps, obs.positions, o);
  std::cout << r.brief_report << "\n" << "Ceres stopped: " << r.termination << "\n" << r.describe();

  std::vector<std::string> comment = {"sflsh fit --avatar " + a.avatar + " --observed " + a.observed + " --params " +
                                      a.params + " --regions " + a.regions};
  char buf[200];
  std::snprintf(buf, sizeof buf, "surface error RMS %.3f mm -> %.3f mm; Ceres: %s", r.rms_before * 1e3,
                r.rms_after * 1e3, r.termination.c_str());
  comment.push_back(buf);
  if (params.damping_index() >= 0) {
    std::snprintf(buf, sizeof buf, "fitted damping: %.6g s (pass --damping %.6g to sflsh simulate)", r.damping, r.damping);
    comment.push_back(buf);
  }
  for (const std::string& w : r.warnings) comment.push_back(w);
  write_fit_error_svg(r, plot, "sflsh fit: " + std::filesystem::path(a.observed).filename().string());
  write_material_file(a.out, r.materials, comment);
  std::cout << "wrote " << a.out << " and " << plot << "\n";
}

const CommandRegistrar reg(75, [](CLI::App& app) {
  auto a = std::make_shared<FitArgs>();
  auto* cmd = app.add_subcommand("fit",
                                 "Fit per-region material parameters (Young's modulus, Fung c, Poisson, damping) so "
                                 "that simulating the observed motion reproduces the observed skin (Ceres)");
  cmd->add_option("--avatar", a->avatar, "Avatar file from `sflsh precompute`");
  cmd->add_option("--observed", a->observed,
                  "Observed skin: a result-layout HDF5 file (/frames/time, /frames/positions in the avatar's surface "
                  "vertex order; its run's bones, /steps/bones, are prescribed when it has them) or a .pc2");
  cmd->add_option("--motion", a->motion,
                  "Motion that drove the observations, whose bones are prescribed when the file holds none of its "
                  "run's (default: the file's /meta/motion)");
  cmd->add_option("--params", a->params, "Comma-separated: young, fung_c, poisson, damping")->capture_default_str();
  cmd->add_option("--regions", a->regions, "'all' or comma-separated region names")->capture_default_str();
  cmd->add_option("--out", a->out, "Fitted material file (YAML, as `sflsh simulate --material` reads)");
  cmd->add_option("--plot", a->plot, "Per-frame surface error before/after (SVG; default: OUT_error.svg)");
  cmd->add_option("--material", a->material, "Starting materials (YAML overrides, as simulate --material)");
  cmd->add_option("--dt", a->dt, "Time step (s; default: the file's /meta/dt, else 1/60)");
  cmd->add_option("--damping", a->damping, "Soft-tissue damping (s) when 'damping' is not fitted; its start when it is")
      ->capture_default_str();
  cmd->add_option("--fps", a->fps, "Frame rate of a .pc2 observation")->capture_default_str();
  cmd->add_flag("--start-at-rest", a->start_at_rest, "The observed run started at rest (simulate --start-at-rest)");
  cmd->add_option("--vertex-stride", a->vertex_stride, "Residuals on every n-th vertex")->capture_default_str();
  cmd->add_option("--frame-stride", a->frame_stride, "Residuals on every n-th observed frame")->capture_default_str();
  cmd->add_option("--loss", a->loss, "Robust loss per vertex: none, huber, cauchy")->capture_default_str();
  cmd->add_option("--loss-scale", a->loss_scale, "Where the robust loss bends (m)")->capture_default_str();
  cmd->add_flag("--numeric", a->numeric, "Jacobians by central differences of whole runs instead of sensitivities");
  cmd->add_option("--max-iterations", a->max_iterations, "Ceres iterations")->capture_default_str();
  cmd->add_option("--noise", a->noise, "Add Gaussian noise of this sigma (m) to the observations (synthetic tests)")
      ->capture_default_str();
  cmd->add_option("--seed", a->seed, "Seed of --noise")->capture_default_str();
  cmd->add_option("--write-reference", a->write_reference,
                  "Instead of fitting: write full-FEM observations of --motion (with --material, --seconds, --dt; "
                  "frames at --fps) to this file");
  cmd->add_option("--seconds", a->seconds, "Duration of --write-reference (s)")->capture_default_str();
  cmd->add_option("--dataset", a->dataset,
                  "Instead of one sequence: fit p(beta) = P0 + sum beta_k P_k to the subjects of this YAML file "
                  "(subjects: [{avatar, observed, motion}]); --out is then the map file");
  cmd->add_option("--regularization", a->regularization, "--dataset: weight of sum_k |P_k|^2 (m^2)")
      ->capture_default_str();
  cmd->add_flag("--leave-one-out", a->leave_one_out, "--dataset: also refit without each subject and report its error");
  cmd->add_option("--map", a->map,
                  "Evaluate a --dataset map at --avatar's betas and write its materials to --out (a material file)");
  cmd->callback([a] { run_fit(*a); });
});

}  // namespace
}  // namespace sflsh::cli
