// The benchmark's rows written as CSV, a Markdown table and an SVG plot.
#include "bench/benchmark_internal.hpp"
#include "sflsh/io/atomic_output.hpp"

namespace sflsh {

namespace {

using bench_internal::kNaN;

const RegionError* region_named(const BenchRow& r, const std::string& name) {
  for (const auto& g : r.regions)
    if (g.name == name) return &g;
  return nullptr;
}

}  // namespace

void write_bench_csv(const std::vector<BenchRow>& rows, const std::string& path) {
  io::write_text_file(path, [&](std::ostream& f) {
    // Region columns follow the first row's regions (the reference lists
    // every region with reference motion; a row without one writes nan).
    const std::vector<RegionError> names = rows.empty() ? std::vector<RegionError>() : rows[0].regions;
    f << "method,handles,dt,newton_iters,is_default,ms_median,ms_p95,speedup,err_mean_mm,err_max_mm,rel_err,peak_ratio,"
         "floor_rel_err,ms_inertia,ms_elastic,ms_solve,dynamic_ms_median,peak_mib";
    for (const auto& g : names) f << ",rel_err_" << g.name << ",floor_" << g.name;
    f << "\n";
    char buf[512];
    for (const auto& r : rows) {
      std::snprintf(buf, sizeof buf, "%s,%d,%.6g,%d,%d,%.4g,%.4g,%.4g,%.4g,%.4g,%.4g,%.4g,%.4g", r.method.c_str(),
                    r.handles, r.dt, r.newton_iters, r.is_default ? 1 : 0, r.ms_median, r.ms_p95, r.speedup,
                    r.err_mean_mm, r.err_max_mm, r.rel_err, r.peak_ratio, r.floor_rel_err);
      f << buf;
      std::snprintf(buf, sizeof buf, ",%.4g,%.4g,%.4g,%.4g,%.4g", r.ms_inertia, r.ms_elastic, r.ms_solve,
                    r.dynamic_ms_median, r.peak_mib);
      f << buf;
      for (const auto& g : names) {
        const RegionError* e = region_named(r, g.name);
        std::snprintf(buf, sizeof buf, ",%.4g,%.4g", e ? e->rel_err : kNaN, e ? e->floor_rel_err : kNaN);
        f << buf;
      }
      f << "\n";
    }
  });
}

void write_bench_markdown(const std::vector<BenchRow>& rows, const std::string& path) {
  io::write_text_file(path, [&](std::ostream& f) {
    f << "| method | variant | K | dt (s) | Newton iters | ms/step median | p95 | speedup | err mean (mm) | err max (mm) "
         "| rel_err | floor | peak ratio | inertia / elastic / solve (ms) | dynamic bones ms/step | peak MiB |\n"
         "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
    char buf[512];
    auto num = [](double v) {
      char b[32];
      std::snprintf(b, sizeof b, "%.3f", v);
      return std::isfinite(v) ? std::string(b) : std::string("–");
    };
    auto bold_default = [](const BenchRow& r, const std::string& line) {
      return r.is_default ? std::string(line).replace(2, r.method.size(), "**" + r.method + "**") : line;
    };
    auto ms3 = [](double v) {
      char b[32];
      std::snprintf(b, sizeof b, "%.3g", v);
      return std::isfinite(v) ? std::string(b) : std::string("–");
    };
    for (const auto& r : rows) {
      if (r.method == "floor") {  // a basis measured by its floor alone: no simulation columns
        f << "| " << r.method << " | " << r.label << " | " << r.handles << " | – | – | – | – | – | – | – | – | "
          << num(r.floor_rel_err) << " | – | – | – | – |\n";
        continue;
      }
      const std::string split = std::isfinite(r.ms_solve)
                                    ? ms3(r.ms_inertia) + " / " + ms3(r.ms_elastic) + " / " + ms3(r.ms_solve)
                                    : std::string("–");
      std::snprintf(buf, sizeof buf,
                    "| %s | %s | %d | 1/%.0f | %s | %.3g | %.3g | %.3g | %.3g | %.3g | %.3f | %s | %.3f | %s | %s | %s |\n",
                    r.method.c_str(), r.label.c_str(), r.handles, 1.0 / r.dt,
                    r.newton_iters < 0 ? "to convergence" : std::to_string(r.newton_iters).c_str(), r.ms_median,
                    r.ms_p95, r.speedup, r.err_mean_mm, r.err_max_mm, r.rel_err, num(r.floor_rel_err).c_str(),
                    r.peak_ratio, split.c_str(), ms3(r.dynamic_ms_median).c_str(), ms3(r.peak_mib).c_str());
      f << bold_default(r, buf);
    }
    // Per region: simulated rel_err / floor.
    const std::vector<RegionError> names = rows.empty() ? std::vector<RegionError>() : rows[0].regions;
    if (!names.empty()) {
      f << "\nrel_err per region (simulated / floor):\n\n| method | variant |";
      for (const auto& g : names) f << ' ' << g.name << " |";
      f << "\n|---|---|";
      for (size_t i = 0; i < names.size(); ++i) f << "---|";
      f << "\n";
      for (const auto& r : rows) {
        std::string line = "| " + r.method + " | " + r.label + " |";
        for (const auto& g : names) {
          const RegionError* e = region_named(r, g.name);
          line += " " + (e ? num(e->rel_err) + (std::isfinite(e->floor_rel_err) ? " / " + num(e->floor_rel_err) : "")
                           : std::string("–")) + " |";
        }
        f << bold_default(r, line + "\n");
      }
    }
  });
}

void write_bench_plot_svg(const std::vector<BenchRow>& rows, const std::string& path, const std::string& title) {
  // Log-log axes: x = ms per step, y = relative error (the reference sits at 0
  // error, so it is drawn as a vertical line at its step time).
  const double W = 900, H = 480, L = 80, R = 300, T = 50, B = 60;
  double xmin = 1e9, xmax = 0, ymin = 1e9, ymax = 0;
  for (const auto& r : rows) {
    if (r.method == "floor") continue;
    xmin = std::min(xmin, std::max(r.ms_median, 1e-3));
    xmax = std::max(xmax, r.ms_median);
    if (r.method != "reference") {
      ymin = std::min(ymin, std::max(r.rel_err, 1e-4));
      ymax = std::max(ymax, r.rel_err);
    }
  }
  const double lx0 = std::floor(std::log10(xmin)), lx1 = std::ceil(std::log10(xmax) + 1e-9);
  const double ly0 = std::floor(std::log10(ymin)), ly1 = std::max(std::ceil(std::log10(ymax) + 1e-9), ly0 + 1);
  auto X = [&](double v) { return L + (std::log10(std::max(v, 1e-3)) - lx0) / (lx1 - lx0) * (W - L - R); };
  auto Y = [&](double v) { return H - B - (std::log10(std::max(v, 1e-4)) - ly0) / (ly1 - ly0) * (H - T - B); };
  io::write_text_file(path, [&](std::ostream& f) {
    f << "<svg xmlns='http://www.w3.org/2000/svg' width='" << W << "' height='" << H
      << "' font-family='sans-serif' font-size='12'>\n<rect width='100%' height='100%' fill='white'/>\n";
    f << "<text x='" << W / 2 << "' y='24' text-anchor='middle' font-size='15'>" << title << "</text>\n";
    for (double e = lx0; e <= lx1; ++e)
      f << "<line x1='" << X(std::pow(10, e)) << "' y1='" << T << "' x2='" << X(std::pow(10, e)) << "' y2='" << H - B
        << "' stroke='#ddd'/><text x='" << X(std::pow(10, e)) << "' y='" << H - B + 18 << "' text-anchor='middle'>"
        << std::pow(10, e) << "</text>\n";
    for (double e = ly0; e <= ly1; ++e)
      f << "<line x1='" << L << "' y1='" << Y(std::pow(10, e)) << "' x2='" << W - R << "' y2='" << Y(std::pow(10, e))
        << "' stroke='#ddd'/><text x='" << L - 6 << "' y='" << Y(std::pow(10, e)) + 4 << "' text-anchor='end'>"
        << std::pow(10, e) << "</text>\n";
    f << "<rect x='" << L << "' y='" << T << "' width='" << W - L - R << "' height='" << H - T - B
      << "' fill='none' stroke='black'/>\n";
    f << "<text x='" << (L + W - R) / 2 << "' y='" << H - 18 << "' text-anchor='middle'>ms per step (median, log)</text>\n";
    f << "<text transform='translate(20," << (T + H - B) / 2
      << ") rotate(-90)' text-anchor='middle'>relative soft-displacement error (log)</text>\n";
    int legend = 0;
    for (const auto& r : rows) {
      if (r.method == "floor") continue;  // no simulation: no step time, no simulated error
      std::string label, color;
      char buf[128];
      if (r.method == "reference") {
        std::snprintf(buf, sizeof buf, "full-FEM reference %.0f ms", r.ms_median);
        label = buf;
        color = "#444";
        f << "<line x1='" << X(r.ms_median) << "' y1='" << T << "' x2='" << X(r.ms_median) << "' y2='" << H - B
          << "' stroke='" << color << "' stroke-dasharray='6,4'/>\n";
      } else {
        label = r.label;
        if (r.method == "skinning")
          color = "#d62728";
        else if (r.method == "peer")
          color = "#8c564b";
        else if (r.newton_iters > 1)
          color = "#2ca02c";
        else if (r.dt != rows[0].dt)
          color = "#ff7f0e";
        else if (r.label.find("tets") != std::string::npos || r.label.find("cell") != std::string::npos)
          color = "#9467bd";
        else
          color = "#1f77b4";
        f << "<circle cx='" << X(r.ms_median) << "' cy='" << Y(r.rel_err) << "' r='" << (r.is_default ? 7 : 5)
          << "' fill='" << color << "' stroke='black'/>\n";
      }
      const double ly = T + 14 + 18 * legend++;
      f << "<circle cx='" << W - R + 14 << "' cy='" << ly - 4 << "' r='5' fill='" << color << "'/><text x='" << W - R + 24
        << "' y='" << ly << "'>" << label << "</text>\n";
    }
    f << "</svg>\n";
  });
}

}  // namespace sflsh
