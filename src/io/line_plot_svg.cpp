#include "sflsh/io/line_plot_svg.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>

#include "sflsh/core/error.hpp"
#include "sflsh/io/atomic_output.hpp"

namespace sflsh::io {
namespace {

/// A round tick spacing giving about `n` ticks over [lo, hi].
double tick_step(double lo, double hi, int n) {
  const double raw = (hi - lo) / n;
  const double p = std::pow(10.0, std::floor(std::log10(raw)));
  for (double m : {1.0, 2.0, 5.0, 10.0})
    if (m * p >= raw) return m * p;
  return 10 * p;
}

std::string escape(const std::string& s) {
  std::string o;
  for (char c : s) {
    if (c == '<') o += "&lt;";
    else if (c == '>') o += "&gt;";
    else if (c == '&') o += "&amp;";
    else o += c;
  }
  return o;
}

}  // namespace

const char* plot_color(int index) {
  static const char* const colors[] = {"#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd", "#8c564b", "#444444"};
  return colors[index % 7];
}

void write_line_plot_svg(const std::string& path, const std::string& title, const std::string& x_label,
                         const std::string& y_label, const std::vector<PlotSeries>& series) {
  double x0 = std::numeric_limits<double>::infinity(), x1 = -x0, y0 = x0, y1 = -x0;
  for (const PlotSeries& s : series) {
    require(s.x.size() == s.y.size(), path, ": plot series '", s.label, "' has ", s.x.size(), " x and ", s.y.size(),
            " y values");
    for (size_t i = 0; i < s.x.size(); ++i)
      if (std::isfinite(s.x[i]) && std::isfinite(s.y[i])) {
        x0 = std::min(x0, s.x[i]), x1 = std::max(x1, s.x[i]);
        y0 = std::min(y0, s.y[i]), y1 = std::max(y1, s.y[i]);
      }
  }
  if (!(x0 < x1)) x0 = std::isfinite(x0) ? x0 - 1 : 0, x1 = x0 + 2;
  if (!(y0 < y1)) y0 = std::isfinite(y0) ? y0 - 1 : 0, y1 = y0 + 2;
  y0 = std::min(y0, 0.0);
  const double dx = tick_step(x0, x1, 8), dy = tick_step(y0, y1, 6);
  x0 = std::floor(x0 / dx) * dx, x1 = std::ceil(x1 / dx) * dx;
  y0 = std::floor(y0 / dy) * dy, y1 = std::ceil(y1 / dy) * dy;
  const double W = 860, H = 480, L = 80, R = 230, T = 50, B = 60;
  auto X = [&](double v) { return L + (v - x0) / (x1 - x0) * (W - L - R); };
  auto Y = [&](double v) { return H - B - (v - y0) / (y1 - y0) * (H - T - B); };
  write_text_file(path, [&](std::ostream& f) {
    f << "<svg xmlns='http://www.w3.org/2000/svg' width='" << W << "' height='" << H
      << "' font-family='sans-serif' font-size='12'>\n<rect width='100%' height='100%' fill='white'/>\n";
    f << "<text x='" << (L + W - R) / 2 << "' y='24' text-anchor='middle' font-size='15'>" << escape(title)
      << "</text>\n";
    for (double v = x0; v <= x1 + 1e-9 * dx; v += dx)
      f << "<line x1='" << X(v) << "' y1='" << T << "' x2='" << X(v) << "' y2='" << H - B
        << "' stroke='#e4e4e4'/><text x='" << X(v) << "' y='" << H - B + 18 << "' text-anchor='middle'>"
        << (std::abs(v) < 1e-12 * dx ? 0.0 : v) << "</text>\n";
    for (double v = y0; v <= y1 + 1e-9 * dy; v += dy)
      f << "<line x1='" << L << "' y1='" << Y(v) << "' x2='" << W - R << "' y2='" << Y(v)
        << "' stroke='#e4e4e4'/><text x='" << L - 6 << "' y='" << Y(v) + 4 << "' text-anchor='end'>"
        << (std::abs(v) < 1e-12 * dy ? 0.0 : v) << "</text>\n";
    f << "<rect x='" << L << "' y='" << T << "' width='" << W - L - R << "' height='" << H - T - B
      << "' fill='none' stroke='black'/>\n";
    f << "<text x='" << (L + W - R) / 2 << "' y='" << H - 18 << "' text-anchor='middle'>" << escape(x_label)
      << "</text>\n<text transform='translate(22," << (T + H - B) / 2 << ") rotate(-90)' text-anchor='middle'>"
      << escape(y_label) << "</text>\n";
    for (size_t k = 0; k < series.size(); ++k) {
      const PlotSeries& s = series[k];
      f << "<polyline fill='none' stroke='" << s.color << "' stroke-width='2'"
        << (s.dashed ? " stroke-dasharray='6,4'" : "") << " points='";
      for (size_t i = 0; i < s.x.size(); ++i)
        if (std::isfinite(s.x[i]) && std::isfinite(s.y[i])) f << X(s.x[i]) << "," << Y(s.y[i]) << " ";
      f << "'/>\n";
      const double ly = T + 14 + 20 * double(k);
      f << "<line x1='" << W - R + 16 << "' y1='" << ly << "' x2='" << W - R + 44 << "' y2='" << ly << "' stroke='"
        << s.color << "' stroke-width='2'" << (s.dashed ? " stroke-dasharray='6,4'" : "") << "/><text x='"
        << W - R + 50 << "' y='" << ly + 4 << "'>" << escape(s.label) << "</text>\n";
    }
    f << "</svg>\n";
  });
}

}  // namespace sflsh::io
