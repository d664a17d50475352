#pragma once
// A plain line plot as an SVG file: linear axes with round ticks, one
// polyline per series, a legend. For figures written by benchmarks and
// commands (force–depth curves, per-step forces) without a plotting library.
#include <string>
#include <vector>

namespace sflsh::io {

struct PlotSeries {
  std::string label;
  std::vector<double> x, y;    ///< same length; non-finite points are skipped
  std::string color = "#1f77b4";
  bool dashed = false;
};

/// Writes the plot to `path` (atomically). Throws naming the path when it
/// cannot be written or a series' x and y differ in length.
void write_line_plot_svg(const std::string& path, const std::string& title, const std::string& x_label,
                         const std::string& y_label, const std::vector<PlotSeries>& series);

/// A few distinct colours for series (cycled).
const char* plot_color(int index);

}  // namespace sflsh::io
