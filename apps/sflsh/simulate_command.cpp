// `sflsh simulate`: drive an avatar with a motion, write the result cache,
// optional exports and a picture.
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <limits>

#include "command.hpp"
#include "sflsh/asset/avatar_file.hpp"
#include "sflsh/precompute/precompute.hpp"
#include "sflsh/core/error.hpp"
#include "sflsh/core/interrupt.hpp"
#include "sflsh/core/progress.hpp"
#include "sflsh/core/time_step.hpp"
#include "sflsh/io/atomic_output.hpp"
#include "sflsh/io/input_file.hpp"
#include "sflsh/motion/load_motion.hpp"
#include "sflsh/precompute/file_betas_avatar.hpp"
#include "sflsh/scene/material_file.hpp"
#include "sflsh/scene/result_export.hpp"
#include "sflsh/scene/result_file.hpp"
#include "sflsh/scene/scene_description.hpp"
#include "sflsh/reference/scene_reference_run.hpp"
#include "sflsh/scene/scene_run.hpp"
#include "sflsh/scene_assets/scene_assets.hpp"
#include "sflsh/scene/simulation_run.hpp"

namespace sflsh::cli {
namespace {

struct SimulateArgs {
  std::string scene;  // a scene file (YAML); then the avatar/motion flags do not apply
  std::string avatar, motion = "builtin:jump", out = "result.h5", exp, render, material, dt = "1/60", bones = "dynamic";
  std::string units = "auto", joint_map, cache_dir, checkpoint, resume;
  double seconds = 0, output_fps = 30, start = 0, end = -1, speed = 1, damping = 0;
  double max_rotation_step = NewtonOptions{}.max_rotation_step;
  int newton_iters = 1, render_frames = 6;
  int iterations_after_damping = NewtonOptions{}.iterations_after_damping;
  std::string nonlinearity_tolerance = "auto";
  std::string solver = "reduced";  // scene files: reduced | full (the full-FEM reference)
  long inject_nan_at_step = 0;  // test only (hidden option)
  bool line_search = false, use_file_betas = false, start_at_rest = false,
       mean_dilatation = SimulatorOptions().mean_dilatation;
  bool seconds_given = false;  // --seconds on the command line (0 there is an error, not "the motion's")
  double tracking_tolerance_mm = 20;
  bool strict = false;
};

/// Dynamic bones can lag behind their motion (damped steps, strong contact):
/// a warning when the pelvis strays more than the tolerance from the
/// motion's root; with --strict, an error (the result file is still written).
void check_tracking(const SimulationResult& r, const SimulateArgs& a) {
  if (!r.bones_dynamic || r.pelvis_error_max * 1e3 <= a.tracking_tolerance_mm) return;
  char buf[400];
  std::snprintf(buf, sizeof buf,
                "the pelvis strayed up to %.1f mm from the motion's root (mean %.1f mm; tolerance %.1f mm, "
                "--tracking-tolerance); %d of %d Newton iterations were damped. Try --newton-iters 3, "
                "--iterations-after-damping 10, --max-rotation-step 0 or a smaller --dt",
                r.pelvis_error_max * 1e3, r.pelvis_error_mean * 1e3, a.tracking_tolerance_mm, r.damped,
                r.accepted + r.damped + r.rejected);
  if (a.strict) fail("simulate --strict: ", buf);
  std::cerr << "warning: " << buf << "\n";
}


/// `sflsh simulate scene.yaml`: the scene's outputs, overridden by --out/--export/--render when given.
void run_scene_file(const SimulateArgs& a, bool out_given) {
  SceneDescription scene = read_scene_description(a.scene);
  if (out_given) scene.output.out = a.out;
  if (!a.exp.empty()) scene.output.export_path = a.exp;
  if (!a.render.empty()) scene.output.render = a.render;
  const OutputDescription& out = scene.output;
  // Named as the user gave them: the flag, or the scene's key.
  io::check_output_file(out.out, out_given ? "--out" : "output.out");
  if (!out.render.empty()) io::check_output_file(out.render, a.render.empty() ? "output.render" : "--render");
  if (!out.export_path.empty()) io::check_output_file(out.export_path, a.exp.empty() ? "output.export" : "--export");
  SceneRunOptions o;
  o.checkpoint = a.checkpoint;
  o.resume = a.resume;
  if (!a.resume.empty()) io::require_input_file(a.resume, "--resume");
  if (!a.checkpoint.empty()) io::check_output_file(a.checkpoint, "--checkpoint");
  require(a.solver == "reduced" || (a.checkpoint.empty() && a.resume.empty()),
          "simulate: --checkpoint and --resume run with the reduced solver (the full-FEM reference keeps no checkpoint)");
  prepare_scene_assets(scene, a.cache_dir.empty() ? default_cache_dir() : a.cache_dir);
  SceneContactStats stats;
  SimulationResult r;
  {
    const InterruptScope interrupt_scope;
    try {
      if (a.solver == "full") {
        SceneReferenceOptions ro;
        r = run_scene_reference(scene, ro, &stats);
      } else {
        r = run_scene(scene, o, &stats);
      }
    } catch (SimulationStopped& e) {
      write_simulation_result(e.partial, out.out);  // the numerical guard: the frames made, marked incomplete
      fail(e.what(), "; wrote the ", e.partial.num_frames, " frames before it to ", out.out, " (marked incomplete)");
    }
    throw_if_interrupted("after the last step");
  }
  write_simulation_result(r, out.out);
  std::cout << r.describe() << stats.describe() << "wrote " << out.out << " (" << r.num_frames << " frames)\n";
  if (!stats.tool_steps.empty()) {
    // The tools' forces and anchors per step, next to the result.
    const std::filesystem::path p(out.out);
    const std::string log = (p.parent_path() / (p.stem().string() + "_tools.csv")).string();
    stats.write_tool_log(log);
    std::cout << "wrote " << log << " (force on each tool and its anchors, per step)\n";
  }
  if (!out.export_path.empty()) std::cout << export_result(r, out.export_path) << "\n";
  if (!out.render.empty()) {
    render_result(r, out.render, out.render_frames);
    std::cout << "wrote " << out.render << "\n";
  }
}

void run_simulate(const SimulateArgs& a) {
  require(!a.avatar.empty(), "simulate: give a scene file (sflsh simulate scene.yaml) or --avatar");
  RunOptions o;
  o.sim.h = parse_time_step(a.dt);
  require(a.bones == "dynamic" || a.bones == "kinematic", "--bones must be 'dynamic' or 'kinematic', got '", a.bones, "'");
  o.sim.bones_dynamic = a.bones == "dynamic";
  require(a.newton_iters >= 1 && a.newton_iters <= 100, "--newton-iters must be in [1, 100], got ", a.newton_iters);
  o.sim.newton.iterations = a.newton_iters;
  o.sim.newton.line_search = a.line_search;
  require(std::isfinite(a.max_rotation_step), "--max-rotation-step must be finite");
  o.sim.newton.max_rotation_step = a.max_rotation_step;
  require(a.iterations_after_damping >= 0 && a.iterations_after_damping <= 100,
          "--iterations-after-damping must be in [0, 100], got ", a.iterations_after_damping);
  o.sim.newton.iterations_after_damping = a.iterations_after_damping;
  if (a.nonlinearity_tolerance != "auto") {
    double tol = std::numeric_limits<double>::quiet_NaN();
    size_t used = 0;
    try {
      tol = std::stod(a.nonlinearity_tolerance, &used);
    } catch (const std::exception&) {
    }
    require(used == a.nonlinearity_tolerance.size() && std::isfinite(tol) && tol >= 0,
            "--newton-nonlinearity-tol must be 'auto' or a number >= 0, got '", a.nonlinearity_tolerance, "'");
    o.sim.newton.nonlinearity_tolerance = tol;
  }
  require(a.damping >= 0, "--damping must be >= 0");
  o.sim.damping = a.damping;
  o.sim.mean_dilatation = a.mean_dilatation;
  require(!a.seconds_given || (std::isfinite(a.seconds) && a.seconds > 0),
          "--seconds must be a positive number of seconds, got ", a.seconds);
  require(std::isfinite(a.output_fps) && a.output_fps > 0, "--output-fps must be positive, got ", a.output_fps);
  require(std::isfinite(a.speed) && a.speed > 0, "--speed must be positive, got ", a.speed);
  require(std::isfinite(a.start) && a.start >= 0, "--start must be >= 0 s, got ", a.start);
  require(std::isfinite(a.end), "--end must be a number of seconds, got ", a.end);
  require(a.render_frames >= 1 && a.render_frames <= 1000, "--render-frames must be in [1, 1000], got ", a.render_frames);
  if (!a.resume.empty()) io::require_input_file(a.resume, "--resume");
  o.seconds = a.seconds;
  o.output_fps = a.output_fps;
  o.start_at_rest = a.start_at_rest;
  o.checkpoint = a.checkpoint;
  o.resume = a.resume;
  require(a.inject_nan_at_step >= 0, "--inject-nan-at-step must be >= 0");
  o.inject_nan_at_step = a.inject_nan_at_step;
  // Check every output can be written before spending time simulating.
  io::check_output_file(a.out, "--out");
  if (!a.render.empty()) io::check_output_file(a.render, "--render");
  if (!a.exp.empty()) io::check_output_file(a.exp, "--export");
  if (!a.checkpoint.empty()) io::check_output_file(a.checkpoint, "--checkpoint");

  if (a.use_file_betas)
    require(a.motion.rfind("builtin:", 0) != 0 && io::lower_extension(a.motion) == ".npz",
            "--use-file-betas needs an AMASS .npz motion (it builds the avatar for the file's 'betas'), got --motion '",
            a.motion, "'");

  auto avatar = std::make_shared<Avatar>(read_avatar(a.avatar));
  std::string avatar_name = a.avatar;

  MotionOptions mo;
  mo.start = a.start;
  mo.end = a.end;
  mo.speed = a.speed;
  mo.units = a.units;
  mo.joint_map = a.joint_map;
  mo.rest_joints = avatar->joints_rest;
  mo.builtin_seconds = a.seconds > 0 ? a.seconds : 5.0;
  MotionReport mrep;
  MotionClip motion = load_motion(a.motion, mo, &mrep);
  if (a.use_file_betas) {
    require(mrep.betas.size() > 0, a.motion, ": --use-file-betas: the file has no 'betas' key (the subject's shape)");
    FileBetasReport brep;
    const std::string cache = a.cache_dir.empty() ? default_cache_dir() : a.cache_dir;
    avatar = std::make_shared<Avatar>(avatar_for_file_betas(*avatar, a.avatar, mrep.betas, cache, &brep));
    std::cout << brep.describe();
    avatar_name = brep.avatar_path;
    // The AMASS axis change uses the avatar's rest pelvis: read again for the shaped skeleton.
    mo.rest_joints = avatar->joints_rest;
    motion = load_motion(a.motion, mo, &mrep);
  }
  if (!a.material.empty()) apply_material_file(a.material, avatar->materials);
  log_info(mrep.describe());  // not with --quiet: then an error is the only line

  // Frames stream into the result file; exports and the picture read it back.
  // SIGINT/SIGTERM stop the run between steps; the writer's partial file is
  // removed as the exception leaves this block.
  o.keep_frames = false;
  {
    const InterruptScope interrupt_scope;
    try {
      ResultWriter writer(a.out, avatar->surface_faces, avatar->surface_rest, avatar->num_reduced());
      SimulationResult r;
      try {
        r = run_simulation(avatar, motion, o, [&](const FrameData& f) { writer.add_frame(f); });
      } catch (SimulationStopped& e) {
        r = std::move(e.partial);  // the numerical guard: keep the frames made, marked incomplete
      }
      r.avatar = avatar_name;
      throw_if_interrupted("after the last step");
      writer.finish(r);
      if (r.incomplete)
        fail(r.stop_reason, "; wrote the ", writer.num_frames(), " frames before it to ", a.out, " (marked incomplete)");
      std::cout << r.describe() << "wrote " << a.out << " (" << writer.num_frames() << " frames)\n";
      check_tracking(r, a);
    } catch (const Interrupted& e) {
      const std::string partial = a.out + ".partial";
      throw Interrupted(std::string(e.what()) + "; " +
                            (std::filesystem::exists(partial) ? "could not remove " : "removed ") + partial +
                            ", no result written",
                        e.signal());
    }
  }
  if (!a.exp.empty() || !a.render.empty()) {
    const SimulationResult full = read_simulation_result(a.out);
    if (!a.exp.empty()) std::cout << export_result(full, a.exp) << "\n";
    if (!a.render.empty()) {
      render_result(full, a.render, a.render_frames);
      std::cout << "wrote " << a.render << "\n";
    }
  }
}

const CommandRegistrar reg(40, [](CLI::App& app) {
  auto a = std::make_shared<SimulateArgs>();
  auto* cmd = app.add_subcommand(
      "simulate",
      "Simulate a scene file (bodies, rigid objects, contact; YAML) or one avatar driven by a motion (backward "
      "Euler, reduced soft tissue)");
  cmd->add_option("scene", a->scene,
                  "Scene file (YAML; keys in include/sflsh/scene/scene_description.hpp, examples in apps/scenes/). "
                  "--out/--export/--render override its outputs; the one-avatar flags do not apply");
  cmd->add_option("--avatar", a->avatar, "Avatar file from `sflsh precompute` (without a scene file)");
  cmd->add_option("--motion", a->motion, "builtin:jump|shake|idle, an AMASS .npz, a .bvh, or FBX/DAE/glTF")
      ->capture_default_str();
  cmd->add_option("--dt", a->dt, "Time step in seconds (e.g. 1/60)")->capture_default_str();
  auto* seconds = cmd->add_option("--seconds", a->seconds, "Simulated duration (default: the motion's, 5 s for built-ins)");
  cmd->add_option("--newton-iters", a->newton_iters, "Newton iterations per step")->capture_default_str();
  cmd->add_flag("--line-search", a->line_search, "Backtracking line search on the step objective");
  cmd->add_flag("--mean-dilatation,!--volume-per-tet", a->mean_dilatation,
                "Average the small-strain volume change per handle cell (B-bar against the subspace's locking; "
                "the default), or integrate every tet's own (--volume-per-tet)");
  cmd->add_option("--max-rotation-step", a->max_rotation_step,
                  "Largest bone rotation per Newton iteration (rad); larger steps are scaled down as a whole "
                  "(counted as damped); <= 0: no cap")
      ->capture_default_str();
  cmd->add_option("--iterations-after-damping", a->iterations_after_damping,
                  "When a step's last Newton iteration is damped by a cap, up to this many more are taken, until "
                  "one is taken in full (keeps dynamic bones on their motion; 0: none)")
      ->capture_default_str();
  cmd->add_option("--newton-nonlinearity-tol", a->nonlinearity_tolerance,
                  "One more Newton iteration (with line search) when a full step's energy change departs from the "
                  "quadratic model's by more than this share (|rho - 1|; 0: off; auto: 0.05 with --bones "
                  "kinematic, off with dynamic bones, whose rotations would trigger it on most steps)")
      ->capture_default_str();
  cmd->add_option("--bones", a->bones, "'dynamic' (bones are DoFs tracking the motion) or 'kinematic' (prescribed)")
      ->capture_default_str();
  cmd->add_flag("--start-at-rest", a->start_at_rest,
                "Start at rest in the motion's first pose (default: moving with the motion's initial velocity)");
  cmd->add_option("--damping", a->damping, "Stiffness-proportional damping of the soft tissue (s)")->capture_default_str();
  cmd->add_option("--material", a->material, "YAML file overriding material parameters per region");
  cmd->add_option("--output-fps", a->output_fps, "Frames written per simulated second")->capture_default_str();
  cmd->add_option("--start", a->start, "Motion start time (s)");
  cmd->add_option("--end", a->end, "Motion end time (s)");
  cmd->add_option("--speed", a->speed, "Motion playback speed factor")->capture_default_str();
  cmd->add_option("--units", a->units, "BVH/assimp length unit: auto, m, cm, mm, inch, cmu")
      ->check(CLI::IsMember({"auto", "m", "cm", "mm", "inch", "cmu"}))
      ->capture_default_str();
  cmd->add_option("--joint-map", a->joint_map, "Joint-name map file for BVH/FBX skeletons ('source smpl' per line)");
  cmd->add_flag("--use-file-betas", a->use_file_betas,
                "AMASS .npz motions: simulate an avatar of the file's 'betas' (same body model and handle count as "
                "--avatar; built once, then reused from --cache-dir)");
  cmd->add_option("--cache-dir", a->cache_dir,
                  "Cache of template stages and --use-file-betas avatars (default: $SFLSH_CACHE_DIR or ~/.cache/sflsh)");
  cmd->add_option("--out", a->out, "Result file (HDF5)")->capture_default_str();
  cmd->add_option("--tracking-tolerance", a->tracking_tolerance_mm,
                  "Dynamic bones: warn when the pelvis strays farther than this from the motion's root (mm)")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  cmd->add_flag("--strict", a->strict, "Exit non-zero (after writing the result) when the tracking tolerance is exceeded");
  cmd->add_option("--checkpoint", a->checkpoint,
                  "Also save the final state (HDF5; a scene's tools' grasps with it) to continue from with --resume");
  cmd->add_option("--resume", a->resume,
                  "Continue from a --checkpoint file: same avatar, motion and options (--seconds is the end time), "
                  "or the same scene file (its end is the scene's)");
  cmd->add_option("--export", a->exp, "Also write result.pc2 (+ rest mesh), an animated result.glb, or frames_%04d.obj/.ply/.glb");
  cmd->add_option("--render", a->render, "Also write a PNG strip of frames coloured by soft displacement");
  cmd->add_option("--render-frames", a->render_frames, "Frames in the --render strip")->capture_default_str();
  // Test only, hidden from --help: drives the run into the numerical guard.
  cmd->add_option("--solver", a->solver,
                  "Scene files: 'reduced' (the avatar's subspace, default) or 'full' (the full-FEM reference: every "
                  "tet node a DoF, bones prescribed; seconds per step)")
      ->check(CLI::IsMember({"reduced", "full"}))
      ->capture_default_str();
  cmd->add_option("--inject-nan-at-step", a->inject_nan_at_step,
                  "TEST ONLY: a NaN motion target at step N (the run must stop there, result marked incomplete)")
      ->group("");
  cmd->callback([a, seconds, cmd] {
    a->seconds_given = seconds->count() > 0;
    if (!a->scene.empty()) {
      for (const char* flag : {"--avatar", "--motion", "--dt", "--seconds", "--bones", "--newton-iters", "--material"})
        require(cmd->count(flag) == 0, "simulate: ", flag, " does not apply to a scene file (", a->scene,
                "); set it in the scene");
      run_scene_file(*a, cmd->count("--out") > 0);
    } else {
      require(a->solver == "reduced", "simulate: --solver full runs scene files (sflsh simulate scene.yaml --solver "
              "full); for a motion, sflsh bench compares the solvers");
      run_simulate(*a);
    }
  });
});

}  // namespace
}  // namespace sflsh::cli
