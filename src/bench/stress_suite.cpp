#include "sflsh/bench/stress_suite.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>

#include <unistd.h>

#include "sflsh/core/error.hpp"
#include "sflsh/core/time_step.hpp"
#include "sflsh/io/atomic_output.hpp"
#include "sflsh/io/line_plot_svg.hpp"
#include "sflsh/scene/scene_description.hpp"
#include "sflsh/scene_assets/scene_assets.hpp"
#include "sflsh/scene/scene_run.hpp"
#include "sflsh/sim/energies/elastic.hpp"

namespace sflsh {
namespace {

std::string fmt(double v, int digits = 3) {
  char b[64];
  std::snprintf(b, sizeof b, "%.*f", digits, v);
  return b;
}

/// StressOptions with the limits of case `case_name`.
StressOptions case_options(const std::string& case_name) {
  const StressCaseLimits limits = stress_case_limits(case_name);
  StressOptions o;
  o.max_rejected = limits.max_rejected;
  o.max_damped_per_step = limits.max_damped_per_step;
  return o;
}

StressCaseResult motion_case(std::shared_ptr<const Avatar> avatar, const std::string& case_name,
                             const std::string& name, const std::string& motion, double dt, double speed, long steps,
                             int window) {
  StressOptions o = case_options(case_name);
  o.motion = motion;
  o.dt = dt;
  o.speed = speed;
  o.steps = steps;
  o.window = window;
  std::fprintf(stderr, "stress-suite: %s (%s, %.0fx, dt 1/%.0f)\n", name.c_str(), motion.c_str(), speed, 1.0 / dt);
  const StressReport r = run_stress(avatar, o);
  return stress_case_result(name, motion + (speed != 1 ? " at " + fmt(speed, 0) + "x" : "") + ", dt 1/" + fmt(1.0 / dt, 0) +
                               ", bones dynamic",
                     dt, r, true);
}

/// A scene file run through the scene code for `steps` steps with the suite's avatar.
StressCaseResult scene_case(const Avatar& avatar, const StressSuiteOptions& o, const StressCaseSpec& spec) {
  const std::string& name = spec.name;
  const std::string path = (std::filesystem::path(o.scenes_dir) / (name + ".yaml")).string();
  require(std::filesystem::is_regular_file(path), path, ": scene file not found (give --scenes-dir)");
  // Read as if it lay in a folder whose avatar.h5 is the suite's avatar (the
  // scenes name "avatar.h5" next to them; it need not exist in the repository).
  const std::filesystem::path tmp =
      std::filesystem::temp_directory_path() / ("sflsh-stress-suite-" + std::to_string(::getpid()));
  std::filesystem::create_directories(tmp);
  const std::filesystem::path link = tmp / "avatar.h5";
  std::error_code ec;
  std::filesystem::remove(link, ec);
  std::filesystem::create_symlink(std::filesystem::absolute(o.avatar_path), link);
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  SceneDescription scene;
  try {
    scene = parse_scene_description(text.str(), (tmp / std::filesystem::path(path).filename()).string());
  } catch (...) {
    std::filesystem::remove_all(tmp, ec);
    throw;
  }
  for (BodyDescription& b : scene.bodies) b.avatar = std::filesystem::absolute(o.avatar_path).string();
  std::filesystem::remove_all(tmp, ec);
  require(scene.bodies.size() == 1, path, ": the stress suite runs one-body scenes, this one has ", scene.bodies.size());
  prepare_scene_assets(scene, "", false);  // mesh shapes baked (no cache)
  if (spec.dt > 0) scene.solver.dt = spec.dt;
  const double dt = scene.solver.dt;
  scene.solver.seconds = double(o.steps) * dt;
  // One output frame per window; a run shorter than two windows, one per step
  // (its growth check reads steps, StressOptions::growth_limit).
  const bool short_run = o.steps < 2L * o.window;
  scene.output.fps = 1.0 / ((short_run ? 1.0 : double(o.window)) * dt);
  std::fprintf(stderr, "stress-suite: %s (scene %s, dt 1/%.0f, %ld steps)\n", name.c_str(), path.c_str(), 1.0 / dt,
               o.steps);
  const std::string setup = "scene " + std::filesystem::path(path).filename().string() + ", dt 1/" + fmt(1.0 / dt, 0) +
                            ", " + std::to_string(scene.solver.newton_iterations) + " Newton it., bones " +
                            (scene.bodies[0].bones_dynamic ? "dynamic" : "kinematic") + ", motion " +
                            scene.bodies[0].motion;
  SimulationResult r;
  SceneRunOptions ro;
  SceneContactStats contact;
  bool finite = true;
  std::string stop;
  try {
    r = run_scene(scene, ro, &contact);
  } catch (SimulationStopped& e) {
    r = std::move(e.partial);
    finite = false;
    stop = e.what();
  }
  // The run as a stress report, one window per output frame (the frame's
  // figures, sampled every `window` steps), judged as the motion cases are.
  StressOptions so = case_options(name);
  so.window = o.window;
  so.growth_reference_share = 0.5;
  so.pelvis_tolerance_mm = 0;  // checked where a motion root exists, below
  StressReport rep;
  rep.steps = long(r.step_outcome.size());
  rep.planned_steps = o.steps;
  rep.finite = finite;
  rep.rejected = r.rejected;
  rep.damped = r.damped;
  rep.accepted = r.accepted;
  rep.ms_median = r.median_step_ms();
  const ElasticTerm elastic(avatar);
  // Frame 0 is the state before the first step (at rest): not the end of a window.
  for (size_t f = 1; f < r.frame_reduced.size(); ++f) {
    StressWindow w;
    w.t_end = r.frame_time[f];
    w.min_det = elastic.min_det(r.frame_reduced[f]);
    w.peak_soft_mm = 1e3 * r.frame_displacement[f].rowwise().norm().maxCoeff();
    rep.windows.push_back(w);
    if (short_run) rep.step_peak_soft_mm.push_back(w.peak_soft_mm);
  }
  // A motion root exists only for dynamic bones following a motion.
  const bool has_root = scene.bodies[0].bones_dynamic && scene.bodies[0].motion != "none" && r.pelvis_frames > 0;
  if (has_root) {
    so.pelvis_tolerance_mm = StressOptions().pelvis_tolerance_mm;
    rep.pelvis_error_max_mm = 1e3 * r.pelvis_error_max;
    rep.pelvis_error_mean_mm = 1e3 * r.pelvis_error_mean;
  }
  judge_stress(rep, so);
  StressCaseResult c = stress_case_result(spec.spec, setup, dt, rep, has_root);
  if (!finite) c.message = stop;
  c.max_penetration_mm = 0;  // no pair came into contact: nothing penetrated
  for (const SceneContactStats::Pair& p : contact.pairs)
    c.max_penetration_mm = std::max(c.max_penetration_mm, 1e3 * p.max_penetration);
  check_stress_case_penetration(c, stress_case_limits(name));
  return c;
}

}  // namespace

StressCaseLimits stress_case_limits(const std::string& name) {
  StressCaseLimits l;  // 0 rejected everywhere
  if (name == "shake") {
    l.max_damped_per_step = 0.01;
  } else if (name == "torture") {
    l.max_damped_per_step = 2.0;
  } else if (name == "cmu_2x" || name == "cmu_3x") {
    l.max_damped_per_step = 1.0;
  } else if (name == "fall_on_floor") {
    l.max_damped_per_step = 1.0;
    l.max_penetration_mm = 5;
  } else if (name == "box_press") {
    l.max_damped_per_step = 1.0;
    l.max_penetration_mm = 10;
  } else {
    fail("stress suite: no limits for unknown case '", name, "'");
  }
  return l;
}

StressCaseResult stress_case_result(const std::string& name, const std::string& setup, double dt, const StressReport& r,
                                    bool has_root) {
  StressCaseResult c;
  c.name = name;
  c.setup = setup;
  c.dt = dt;
  c.steps = r.steps;
  c.finite = r.finite;
  c.rejected = r.rejected;
  c.damped = r.damped;
  c.min_det = r.min_det;
  c.peak_soft_mm = r.peak_soft_mm;
  c.peak_soft_mm_early = r.peak_soft_mm_early;
  c.peak_soft_mm_late = r.peak_soft_mm_late;
  if (has_root) {
    c.pelvis_max_mm = r.pelvis_error_max_mm;
    c.pelvis_mean_mm = r.pelvis_error_mean_mm;
  }
  c.ms_median = r.ms_median;
  for (const StressWindow& w : r.windows) {
    c.window_t.push_back(w.t_end);
    c.window_peak_soft_mm.push_back(w.peak_soft_mm);
  }
  if (!r.passed()) {
    c.status = "FAILED";
    c.message = r.failure();
  }
  return c;
}

void check_stress_case_penetration(StressCaseResult& c, const StressCaseLimits& limits) {
  if (limits.max_penetration_mm < 0 || c.status == "FAILED") return;
  if (c.max_penetration_mm < 0) {
    c.status = "FAILED";
    c.message = "no contact pair recorded (a penetration limit of " + fmt(limits.max_penetration_mm, 1) + " mm is set)";
  } else if (!(c.max_penetration_mm <= limits.max_penetration_mm)) {
    c.status = "FAILED";
    c.message = "penetration " + fmt(c.max_penetration_mm, 2) + " mm (at most " + fmt(limits.max_penetration_mm, 1) +
                " mm)";
  }
}

const std::vector<std::string>& stress_suite_case_names() {
  static const std::vector<std::string> names = {"shake", "torture", "cmu_2x", "cmu_3x", "fall_on_floor", "box_press"};
  return names;
}

const std::vector<std::string>& stress_suite_default_cases() {
  static const std::vector<std::string> cases = {"shake@1/30",  "shake@1/15",    "torture@1/30", "cmu_2x@1/30",
                                                 "cmu_3x@1/30", "fall_on_floor", "box_press"};
  return cases;
}

StressCaseSpec parse_stress_case(const std::string& spec, const std::string& option) {
  StressCaseSpec c;
  c.spec = spec;
  const size_t at = spec.find('@');
  c.name = spec.substr(0, at);
  const std::vector<std::string>& known = stress_suite_case_names();
  std::string list;
  for (const std::string& n : known) list += (list.empty() ? "" : ", ") + n;
  require(std::find(known.begin(), known.end(), c.name) != known.end(), option, ": unknown case '", c.name,
          "' in '", spec, "' (known: ", list, "; write NAME or NAME@DT, e.g. shake@1/30)");
  if (at != std::string::npos) c.dt = parse_time_step(spec.substr(at + 1), option + " " + spec + ": dt");
  return c;
}

void validate_stress_suite_options(const StressSuiteOptions& o) {
  for (const std::string& c : o.cases) parse_stress_case(c);
  require(o.steps >= 1, "--steps must be >= 1, got ", o.steps);
  require(o.window >= 1, "--window must be >= 1, got ", o.window);
}

std::vector<StressCaseResult> run_stress_suite(std::shared_ptr<const Avatar> avatar, const StressSuiteOptions& o,
                                               const std::function<void(const std::vector<StressCaseResult>&)>& on_case) {
  validate_stress_suite_options(o);
  const std::vector<std::string>& specs = o.cases.empty() ? stress_suite_default_cases() : o.cases;
  std::vector<StressCaseResult> out;
  for (const std::string& spec : specs) {
    const StressCaseSpec c = parse_stress_case(spec);
    const double dt = c.dt > 0 ? c.dt : 1.0 / 30;
    try {
      if (c.name == "shake") out.push_back(motion_case(avatar, c.name, spec, "builtin:shake", dt, 1, o.steps, o.window));
      if (c.name == "torture") out.push_back(motion_case(avatar, c.name, spec, "builtin:torture", dt, 1, o.steps, o.window));
      if (c.name == "cmu_2x" || c.name == "cmu_3x") {
        const double speed = c.name == "cmu_2x" ? 2 : 3;
        std::vector<std::string> files;
        std::error_code ec;
        if (!o.mocap_dir.empty() && std::filesystem::is_directory(o.mocap_dir, ec))
          for (const auto& e : std::filesystem::directory_iterator(o.mocap_dir, ec))
            if (e.path().extension() == ".bvh") files.push_back(e.path().string());
        std::sort(files.begin(), files.end());
        if (files.empty()) {
          StressCaseResult r;
          r.name = spec;
          r.status = "skipped";
          r.message = "no .bvh files in the mocap folder '" + o.mocap_dir + "' (give --mocap-dir)";
          std::fprintf(stderr, "stress-suite: %s skipped: %s\n", spec.c_str(), r.message.c_str());
          out.push_back(r);
        }
        for (const std::string& f : files)
          out.push_back(motion_case(avatar, c.name, spec + "/" + std::filesystem::path(f).stem().string(), f, dt,
                                    speed, o.steps, o.window));
      }
      if (c.name == "fall_on_floor" || c.name == "box_press") out.push_back(scene_case(*avatar, o, c));
    } catch (const Error& e) {
      StressCaseResult r;
      r.name = spec;
      r.status = "FAILED";
      r.message = e.what();
      std::fprintf(stderr, "stress-suite: %s failed: %s\n", spec.c_str(), e.what());
      out.push_back(r);
    }
    if (on_case) on_case(out);
  }
  return out;
}

void write_stress_suite_csv(const std::vector<StressCaseResult>& results, const std::string& path) {
  io::write_text_file(path, [&](std::ostream& f) {
    f << "case,status,dt,steps,nan,rejected,damped,min_det,peak_soft_mm,pelvis_max_mm,pelvis_mean_mm,ms_median,"
         "max_penetration_mm,peak_soft_early_mm,peak_soft_late_mm,setup,message\n";
    for (const StressCaseResult& c : results) {
      const bool ran = c.status != "skipped";
      f << c.name << ',' << c.status << ',' << c.dt << ',' << c.steps << ',' << (c.finite ? 0 : 1) << ',' << c.rejected
        << ',' << c.damped << ',' << (ran ? fmt(c.min_det, 4) : "") << ',' << (ran ? fmt(c.peak_soft_mm, 2) : "")
        << ',' << (c.pelvis_max_mm >= 0 ? fmt(c.pelvis_max_mm, 2) : "") << ','
        << (c.pelvis_mean_mm >= 0 ? fmt(c.pelvis_mean_mm, 2) : "") << ',' << (ran ? fmt(c.ms_median, 2) : "") << ','
        << (c.max_penetration_mm >= 0 ? fmt(c.max_penetration_mm, 2) : "") << ','
        << (ran ? fmt(c.peak_soft_mm_early, 2) : "") << ',' << (ran ? fmt(c.peak_soft_mm_late, 2) : "") << ",\""
        << c.setup << "\",\"" << c.message << "\"\n";
    }
  });
}

void write_stress_suite_markdown(const std::vector<StressCaseResult>& results, const std::string& path,
                                 const std::string& command) {
  io::write_text_file(path, [&](std::ostream& f) {
    f << "# Stress suite\n\n`" << command << "`\n\n"
      << "| case | setup | steps | NaN | rejected | damped | min det F | peak soft (mm) | pelvis max / mean (mm) | "
         "median step (ms) | max penetration (mm) | status |\n|---|---|---|---|---|---|---|---|---|---|---|---|\n";
    for (const StressCaseResult& c : results) {
      if (c.status == "skipped") {
        f << "| " << c.name << " | | | | | | | | | | | skipped: " << c.message << " |\n";
        continue;
      }
      f << "| " << c.name << " | " << c.setup << " | " << c.steps << " | " << (c.finite ? 0 : 1) << " | " << c.rejected
        << " | " << c.damped << " | " << fmt(c.min_det) << " | " << fmt(c.peak_soft_mm, 1) << " | "
        << (c.pelvis_max_mm >= 0 ? fmt(c.pelvis_max_mm, 1) + " / " + fmt(c.pelvis_mean_mm, 1) : "–") << " | "
        << fmt(c.ms_median, 2) << " | " << (c.max_penetration_mm >= 0 ? fmt(c.max_penetration_mm, 2) : "–") << " | "
        << c.status << (c.message.empty() ? "" : ": " + c.message) << " |\n";
    }
  });
}

void write_stress_suite_svg(const std::vector<StressCaseResult>& results, const std::string& path) {
  std::vector<io::PlotSeries> series;
  for (const StressCaseResult& c : results) {
    if (c.window_t.empty() || c.name.rfind("cmu_", 0) == 0) continue;  // CMU clips are seconds long: table only
    io::PlotSeries s;
    s.label = c.name;
    s.x = c.window_t;
    s.y = c.window_peak_soft_mm;
    s.color = io::plot_color(int(series.size()));
    series.push_back(std::move(s));
  }
  io::write_line_plot_svg(path, "sflsh stress-suite: peak soft displacement per window", "simulated time (s)",
                          "peak soft displacement (mm)", series);
}

}  // namespace sflsh
