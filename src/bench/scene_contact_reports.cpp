// What `sflsh bench-contact --scene` writes: per scene its series (CSV) and
// plot (SVG), a summary CSV and the Markdown section of contact_bench.md.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ostream>

#include "sflsh/bench/scene_contact_benchmark.hpp"
#include "sflsh/core/error.hpp"
#include "sflsh/io/atomic_output.hpp"
#include "sflsh/io/line_plot_svg.hpp"

namespace sflsh {
namespace {

/// A number as "%.*f", or "—" when it is not finite.
std::string fixed(double v, int digits) {
  if (!std::isfinite(v)) return "—";
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", digits, v);
  return buf;
}

/// A share as a whole percentage, or "—".
std::string percent(double v) { return std::isfinite(v) ? fixed(100.0 * v, 0) + " %" : "—"; }

bool all_have_depth(const SceneContactBenchResult& r) {
  for (const SceneContactPair& p : r.pairs)
    if (!std::isfinite(p.max_depth_mm)) return false;
  return !r.pairs.empty();
}

}  // namespace

void write_scene_contact_series_csv(const SceneContactBenchResult& r, const std::string& path) {
  io::write_text_file(path, [&](std::ostream& f) {
    f << "step,time_s,object,depth_mm,force_full_n,force_reduced_n,dent_full_mm,dent_reduced_mm,patch_nodes\n";
    char buf[512];
    for (size_t k = 0; k < r.time.size(); ++k)
      for (const SceneContactPair& p : r.pairs) {
        std::snprintf(buf, sizeof buf, "%zu,%.6g,%s,%.6g,%.6g,%.6g,%.6g,%.6g,%d\n", k + 1, r.time[k], p.object.c_str(),
                      p.depth_mm.at(k), p.force_full_n.at(k), p.force_reduced_n.at(k), p.dent_full_mm.at(k),
                      p.dent_reduced_mm.at(k), p.patch_nodes.at(k));
        f << buf;
      }
  });
}

void write_scene_contact_plot_svg(const SceneContactBenchResult& r, const std::string& path) {
  const bool by_depth = all_have_depth(r);
  std::vector<io::PlotSeries> series;
  int c = 0;
  for (const SceneContactPair& p : r.pairs) {
    std::vector<double> x = by_depth ? p.depth_mm : r.time, full = p.force_full_n, reduced = p.force_reduced_n;
    if (by_depth) {  // the loading part: from the step before first contact to the deepest step
      const size_t n = size_t(std::max_element(x.begin(), x.end()) - x.begin()) + 1;
      size_t first = 0;
      while (first < n && !(full[first] > 0)) ++first;
      const long from = long(first > 0 ? first - 1 : 0);
      x = std::vector<double>(x.begin() + from, x.begin() + long(n));
      full = std::vector<double>(full.begin() + from, full.begin() + long(n));
      reduced = std::vector<double>(reduced.begin() + from, reduced.begin() + long(n));
    }
    const std::string color = io::plot_color(c++);
    const std::string name = r.pairs.size() > 1 ? p.object + ": " : "";
    series.push_back({name + "full FEM", x, full, color, true});
    char label[64];
    std::snprintf(label, sizeof label, "reduced (peak %+.0f %%)", 100.0 * (p.peak_reduced_n / p.peak_full_n - 1.0));
    series.push_back({name + label, x, reduced, color, false});
  }
  io::write_line_plot_svg(path, r.scene + ": contact force, reduced vs. full FEM",
                          by_depth ? "depth: the object's travel since first contact (mm)" : "time (s)",
                          "contact force on the body (N)", series);
}

void write_scene_contact_summary_csv(const std::vector<SceneContactBenchResult>& results, const std::string& path) {
  io::write_text_file(path, [&](std::ostream& f) {
    f << "scene,object,peak_full_n,peak_reduced_n,peak_err,rms_err,rms_steps,dent_full_mm,dent_reduced_mm,"
         "max_depth_mm,max_patch_nodes,ms_contact,ms_no_contact,step_ratio,ms_full\n";
    char buf[1024];
    for (const SceneContactBenchResult& r : results)
      for (const SceneContactPair& p : r.pairs) {
        std::snprintf(buf, sizeof buf, "%s,%s,%.4g,%.4g,%.4g,%.4g,%d,%.4g,%.4g,%.4g,%d,%.4g,%.4g,%.4g,%.4g\n",
                      r.scene.c_str(), p.object.c_str(), p.peak_full_n, p.peak_reduced_n, p.peak_err, p.rms_err,
                      p.rms_steps, p.dent_full_max_mm, p.dent_reduced_max_mm, p.max_depth_mm, p.max_patch_nodes,
                      r.ms_contact, r.ms_no_contact, r.step_ratio, r.ms_full);
        f << buf;
      }
  });
}

void write_scene_contact_markdown(const std::vector<SceneContactBenchResult>& results,
                                  const SceneContactBenchSettings& s, std::ostream& f) {
  char buf[4096];
  std::snprintf(
      buf, sizeof buf,
      "Scene files: each run as written by the reduced solver (the scene loop of `sflsh simulate`; its contact is "
      "the scene's contact.patch, or the per-sample penalty without it) and by the full-FEM reference (`sflsh simulate "
      "--solver full`: face samples with the scene's pressure stiffness, frictionless), compared per contact pair and "
      "per grasping tool (the force on the tool through its anchors; its dent: the skin within its sensors' reach) at "
      "every step. Peak force: the largest |contact force on the body| over the steps, its error |reduced − full| / "
      "full; RMS error: of (F_red − F_full) / F_full over the steps where the full FEM's force is above %.0f %% of its "
      "peak (steps counted); dent: the largest soft displacement |u| of the skin within %.0f mm of the object's "
      "surface, over the steps; depth: the object's deepest travel since the full FEM's first contact step, along "
      "its peak force (kinematic objects and tools on a body without a motion; — otherwise); patch nodes: the "
      "reduced run's largest contact patch (— without contact.patch). ms/step: the reduced scene loop's median step "
      "over its steps with contact, with the scene as written and with the compared objects and tools removed "
      "(\"without\"; the same steps), their ratio, and the full FEM's median step over its steps with contact%s.\n\n",
      100.0 * s.force_threshold, 1e3 * s.dent_reach, s.cpu_time ? " (CPU time of the stepping thread)" : "");
  f << buf;
  f << "| scene | object | dt (s) | peak force full / reduced (N) | peak error | RMS error (steps) | dent full / "
       "reduced (mm) | depth (mm) | patch nodes | ms/step contact | ms/step without | ratio | full FEM ms/step |\n"
       "|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
  for (const SceneContactBenchResult& r : results)
    for (const SceneContactPair& p : r.pairs) {
      std::snprintf(buf, sizeof buf, "| %s | %s | 1/%.0f | %.2f / %.2f | %s | %s (%d) | %.2f / %.2f | %s | %s | %.3g | "
                    "%.3g | %.2f | %.3g |\n",
                    r.scene.c_str(), p.object.c_str(), 1.0 / r.dt, p.peak_full_n, p.peak_reduced_n,
                    percent(p.peak_err).c_str(), percent(p.rms_err).c_str(), p.rms_steps, p.dent_full_max_mm,
                    p.dent_reduced_max_mm, fixed(p.max_depth_mm, 1).c_str(),
                    r.patch ? std::to_string(p.max_patch_nodes).c_str() : "—", r.ms_contact, r.ms_no_contact,
                    r.step_ratio, r.ms_full);
      f << buf;
    }
  for (const SceneContactBenchResult& r : results)
    f << "\n" << r.scene << ": " << r.time.size() << " steps, " << r.contact_steps
      << " with contact in the reduced run; without contact: " << r.removed << " removed.";
  f << "\n";
}

}  // namespace sflsh
