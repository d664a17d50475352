#include "sflsh/bench/stress_run.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iomanip>
#include <limits>
#include <sstream>

#include "sflsh/core/error.hpp"
#include "sflsh/core/percentile.hpp"
#include "sflsh/sim/energies/elastic.hpp"
#include "sflsh/scene/torture_motion.hpp"
#include "sflsh/io/atomic_output.hpp"

namespace sflsh {

std::string StressReport::failure() const {
  std::ostringstream o;
  o << std::fixed << std::setprecision(1);
  if (!finite) return "non-finite state";
  if (!no_inversion) return "inverted cubature sample";
  if (!complete) return "ended after " + std::to_string(steps) + " of " + std::to_string(planned_steps) + " steps";
  if (!few_rejected) {
    o << rejected << " rejected steps (at most " << max_rejected << ")";
    return o.str();
  }
  if (!few_damped) {
    o << std::setprecision(2) << damped << " damped Newton iterations in " << steps << " steps ("
      << (steps > 0 ? double(damped) / double(steps) : 0.0) << " per step, at most " << max_damped_per_step << ")";
    return o.str();
  }
  if (!tracking) {
    o << "pelvis " << pelvis_error_max_mm << " mm from the motion's root (> " << pelvis_tolerance_mm << " mm)";
    return o.str();
  }
  if (!stable) {
    o << "soft displacement grew (" << (short_run ? "last tenth of the steps " : "last window ") << peak_soft_mm_late
      << " mm, " << (short_run ? "every step before " : "first windows ") << peak_soft_mm_early << " mm; at most "
      << growth_limit << "x)";
    return o.str();
  }
  return "";
}

std::string StressReport::describe() const {
  std::ostringstream o;
  o << std::fixed << std::setprecision(3);
  o << "stress: " << steps << " steps (" << accepted << " accepted, " << damped << " damped, " << rejected
    << " rejected)\n"
    << "  finite state:            " << (finite ? "yes" : "NO") << "\n"
    << "  min det F over samples:  " << min_det << (no_inversion ? "" : "  (INVERTED)") << "\n"
    << "  steps run / planned:     " << steps << " / " << planned_steps << (complete ? "" : "  (ENDED EARLY)") << "\n"
    << "  rejected / damped:       " << rejected << " (at most " << max_rejected << ") / " << damped << " (at most "
    << max_damped_per_step << " per step)" << (few_rejected ? "" : "  (TOO MANY REJECTED)")
    << (few_damped ? "" : "  (TOO MANY DAMPED)") << "\n"
    << "  peak soft displacement:  " << (short_run ? "steps before the last tenth " : "first windows ")
    << peak_soft_mm_early << " mm, " << (short_run ? "last tenth " : "last window ") << peak_soft_mm_late << " mm"
    << " (at most " << growth_limit << "x)" << (stable ? "" : "  (GROWING)") << "\n"
    << "  pelvis vs motion root:   max " << pelvis_error_max_mm << " mm, mean " << pelvis_error_mean_mm
    << " mm (every step)" << (tracking ? "" : "  (OVER THE TOLERANCE)") << "\n"
    << "  result: " << (passed() ? "PASSED" : "FAILED") << "\n";
  return o.str();
}

void judge_stress(StressReport& r, const StressOptions& o) {
  r.min_det = std::numeric_limits<double>::infinity();
  r.peak_soft_mm = 0;
  for (const StressWindow& x : r.windows) {
    r.min_det = std::min(r.min_det, x.min_det);
    r.peak_soft_mm = std::max(r.peak_soft_mm, x.peak_soft_mm);
  }
  r.peak_soft_mm_early = r.peak_soft_mm_late = 0;
  const std::vector<double>& p = r.step_peak_soft_mm;
  r.short_run = r.steps < 2L * o.window && p.size() >= 2;
  if (r.short_run) {
    // The last tenth of the steps (at least one) against every step before it.
    const size_t late = std::max<size_t>(1, p.size() / 10);
    for (size_t i = 0; i + late < p.size(); ++i) r.peak_soft_mm_early = std::max(r.peak_soft_mm_early, p[i]);
    for (size_t i = p.size() - late; i < p.size(); ++i) r.peak_soft_mm_late = std::max(r.peak_soft_mm_late, p[i]);
  } else {
    // The last window against the first 10 % (growth_reference_share, rounded up) of the windows (one window, a
    // one-step run: itself).
    const size_t early =
        std::max<size_t>(1, size_t(std::ceil(double(r.windows.size()) * o.growth_reference_share - 1e-9)));
    for (size_t i = 0; i < std::min(early, r.windows.size()); ++i)
      r.peak_soft_mm_early = std::max(r.peak_soft_mm_early, r.windows[i].peak_soft_mm);
    if (!r.windows.empty()) r.peak_soft_mm_late = r.windows.back().peak_soft_mm;
  }
  // Written so that NaN figures fail.
  r.no_inversion = r.min_det > 0;
  r.complete = r.steps == r.planned_steps;
  r.growth_limit = r.short_run ? o.short_run_growth_limit : o.growth_limit;
  r.stable = r.peak_soft_mm_late <= r.growth_limit * r.peak_soft_mm_early;
  r.tracking = o.pelvis_tolerance_mm <= 0 || r.pelvis_error_max_mm <= o.pelvis_tolerance_mm;
  r.max_rejected = o.max_rejected;
  r.max_damped_per_step = o.max_damped_per_step;
  r.pelvis_tolerance_mm = o.pelvis_tolerance_mm;
  r.few_rejected = r.rejected <= o.max_rejected;
  r.few_damped = double(r.damped) <= o.max_damped_per_step * double(r.steps);
}

StressReport run_stress(std::shared_ptr<const Avatar> avatar, const StressOptions& o) {
  require(o.steps >= 1, "stress: steps must be >= 1, got ", o.steps);
  require(o.window >= 1, "stress: window must be >= 1, got ", o.window);
  require(o.dt > 0 && std::isfinite(o.dt), "stress: dt must be positive, got ", o.dt);
  require(o.speed > 0 && std::isfinite(o.speed), "stress: speed must be positive, got ", o.speed);
  MotionOptions mo;
  mo.rest_joints = avatar->joints_rest;
  mo.speed = o.speed;
  mo.builtin_seconds = (double(o.steps) * o.dt + 1.0) * o.speed;  // built-ins cover the whole run
  const MotionClip motion = load_stress_motion(o.motion, mo);

  RunOptions ro;
  ro.sim.h = o.dt;
  ro.sim.bones_dynamic = true;
  ro.sim.mean_dilatation = o.mean_dilatation;
  ro.sim.newton.iterations_after_damping = o.iterations_after_damping;
  ro.seconds = std::min(double(o.steps) * o.dt, motion.duration());
  ro.output_fps = 10;  // frames are not kept and not used: the step callback records everything
  ro.keep_frames = false;
  // The pelvis error is sampled after every step (the output frames' 10 fps
  // missed the worst steps of a 2× clip: 28 mm read as lower).
  const long planned = run_step_count(motion, ro);
  const Vec3 pelvis_rest = avatar->joints_rest.row(0).transpose();
  double pelvis_sum = 0;

  StressReport r;
  r.min_det = std::numeric_limits<double>::infinity();
  StressWindow w;
  std::vector<double> ms, all_ms;
  w.min_det = std::numeric_limits<double>::infinity();
  long step = 0;
  ro.on_step = [&](const Simulator& sim, const StepReport& rep) {
    ++step;
    const ElasticTerm* elastic_term = sim.model().find_term<ElasticTerm>(0);
    require(elastic_term != nullptr, "stress: the model has no elastic term");
    const double det = elastic_term->min_det(sim.state().z);
    const double peak = 1e3 * sim.soft_displacement().rowwise().norm().maxCoeff();
    r.step_peak_soft_mm.push_back(peak);
    double elastic = 0;
    for (const TermEnergy& e : rep.energies)
      if (e.name == "elastic") elastic = e.value;
    w.min_det = std::min(w.min_det, det);
    w.peak_soft_mm = std::max(w.peak_soft_mm, peak);
    w.max_elastic_J = std::max(w.max_elastic_J, elastic);
    w.damped += rep.damped;
    w.rejected += rep.rejected;
    ms.push_back(rep.ms_total);
    all_ms.push_back(rep.ms_total);
    r.accepted += rep.accepted;
    r.damped += rep.damped;
    r.rejected += rep.rejected;
    // Simulated pelvis (joint 0) vs the motion's root at this step's time, as run_simulation's frames measure it.
    const Vec3 target = target_bones(*avatar, motion.sample(double(step) * o.dt))[0] * pelvis_rest;
    const double pelvis_mm = 1e3 * (sim.state().bones[0] * pelvis_rest - target).norm();
    r.pelvis_error_max_mm = std::max(r.pelvis_error_max_mm, pelvis_mm);
    pelvis_sum += pelvis_mm;
    r.pelvis_error_mean_mm = pelvis_sum / double(step);
    if (step % o.window == 0) {
      w.t_end = double(step) * o.dt;
      w.ms_median = percentile(ms, 0.5);
      r.windows.push_back(w);
      w = StressWindow();
      w.min_det = std::numeric_limits<double>::infinity();
      ms.clear();
    }
  };
  try {
    run_simulation(avatar, motion, ro);
  } catch (const Error& e) {
    r.finite = false;
    std::fprintf(stderr, "stress: %s\n", e.what());
  }
  r.steps = step;
  if (step % o.window != 0 && !ms.empty()) {  // the last, partial window (a short motion or a stop)
    w.t_end = double(step) * o.dt;
    w.ms_median = percentile(ms, 0.5);
    r.windows.push_back(w);
  }
  if (!all_ms.empty()) r.ms_median = percentile(all_ms, 0.5);
  r.planned_steps = planned;
  judge_stress(r, o);
  return r;
}

void write_stress_csv(const StressReport& r, const std::string& path) {
  io::write_text_file(path, [&](std::ostream& f) {
    f << "t_end,peak_soft_mm,max_elastic_J,min_det,damped,rejected,ms_median\n";
    for (const StressWindow& w : r.windows)
      f << w.t_end << ',' << w.peak_soft_mm << ',' << w.max_elastic_J << ',' << w.min_det << ',' << w.damped << ','
        << w.rejected << ',' << w.ms_median << '\n';
  });
}

void write_stress_plot_svg(const StressReport& r, const std::string& path, const std::string& title) {
  // Three stacked panels sharing the time axis, each scaled to its own range.
  const double W = 900, panel = 150, L = 90, R = 30, T = 40, gap = 30;
  const double H = T + 3 * panel + 2 * gap + 50;
  const double t1 = r.windows.empty() ? 1.0 : r.windows.back().t_end;
  io::write_text_file(path, [&](std::ostream& f) {
    f << "<svg xmlns='http://www.w3.org/2000/svg' width='" << W << "' height='" << H
      << "' font-family='sans-serif' font-size='12'>\n<rect width='100%' height='100%' fill='white'/>\n"
      << "<text x='" << W / 2 << "' y='24' text-anchor='middle' font-size='15'>" << title << "</text>\n";
    struct Series {
      const char* name;
      double StressWindow::*field;
      const char* color;
    };
    const Series series[3] = {{"peak soft displacement (mm)", &StressWindow::peak_soft_mm, "#1f77b4"},
                              {"max elastic energy (J)", &StressWindow::max_elastic_J, "#ff7f0e"},
                              {"min det F over cubature samples", &StressWindow::min_det, "#2ca02c"}};
    for (int p = 0; p < 3; ++p) {
      const double y0 = T + p * (panel + gap);
      double lo = 0, hi = 0;
      for (const StressWindow& w : r.windows) hi = std::max(hi, w.*(series[p].field));
      if (p == 2) {
        lo = hi;
        for (const StressWindow& w : r.windows) lo = std::min(lo, w.*(series[p].field));
        lo = std::min(lo, 0.0);
        hi = std::max(hi, 1.0);
      }
      if (hi <= lo) hi = lo + 1;
      auto X = [&](double t) { return L + t / t1 * (W - L - R); };
      auto Y = [&](double v) { return y0 + panel - (v - lo) / (hi - lo) * panel; };
      f << "<rect x='" << L << "' y='" << y0 << "' width='" << W - L - R << "' height='" << panel
        << "' fill='none' stroke='black'/>\n<text x='" << L + 6 << "' y='" << y0 + 14 << "'>" << series[p].name
        << "</text>\n<text x='" << L - 6 << "' y='" << y0 + 12 << "' text-anchor='end'>" << hi << "</text>\n<text x='"
        << L - 6 << "' y='" << y0 + panel << "' text-anchor='end'>" << lo << "</text>\n<polyline fill='none' stroke='"
        << series[p].color << "' stroke-width='1.5' points='";
      for (const StressWindow& w : r.windows) f << X(w.t_end) << ',' << Y(w.*(series[p].field)) << ' ';
      f << "'/>\n";
    }
    f << "<text x='" << (L + W - R) / 2 << "' y='" << H - 12 << "' text-anchor='middle'>simulated time (s), 0 to " << t1
      << "</text>\n</svg>\n";
  });
}

}  // namespace sflsh
