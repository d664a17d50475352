#include "sflsh/io/colormap.hpp"

#include <algorithm>
#include <array>
#include <cmath>

#include "sflsh/core/error.hpp"

namespace sflsh::io {

namespace {

/// viridis sampled at t = 0, 0.1, ..., 1 (matplotlib's published table,
/// the 11 standard stops); linear interpolation between stops is within a
/// few 1/255 of the full 256-entry table.
constexpr std::array<std::array<int, 3>, 11> kViridis = {{{68, 1, 84},
                                                          {72, 36, 117},
                                                          {65, 68, 135},
                                                          {53, 95, 141},
                                                          {42, 120, 142},
                                                          {33, 145, 140},
                                                          {34, 168, 132},
                                                          {68, 191, 112},
                                                          {122, 209, 81},
                                                          {189, 223, 38},
                                                          {253, 231, 37}}};

Vec3 viridis(double t) {
  const double s = t * double(kViridis.size() - 1);
  const int i = std::min(int(s), int(kViridis.size()) - 2);
  const double a = s - i;
  Vec3 c;
  for (int k = 0; k < 3; ++k) c[k] = ((1 - a) * kViridis[i][k] + a * kViridis[i + 1][k]) / 255.0;
  return c;
}

/// Turbo by its polynomial fit (Mikhailov, "Turbo, an improved rainbow
/// colormap", Google AI blog 2019, the published GLSL approximation).
Vec3 turbo(double t) {
  const double t2 = t * t, t3 = t2 * t, t4 = t2 * t2, t5 = t4 * t;
  Vec3 c(0.13572138 + 4.61539260 * t - 42.66032258 * t2 + 132.13108234 * t3 - 152.94239396 * t4 + 59.28637943 * t5,
         0.09140261 + 2.19418839 * t + 4.84296658 * t2 - 14.18503333 * t3 + 4.27729857 * t4 + 2.82956604 * t5,
         0.10667330 + 12.64194608 * t - 60.58204836 * t2 + 110.36276771 * t3 - 89.90310912 * t4 + 27.34824973 * t5);
  return c.cwiseMax(0.0).cwiseMin(1.0);
}

}  // namespace

Colormap colormap_from_name(const std::string& name) {
  if (name == "viridis") return Colormap::Viridis;
  if (name == "turbo") return Colormap::Turbo;
  fail("unknown colormap '", name, "'; known: viridis, turbo");
}

Vec3 colormap_rgb(Colormap map, double t) {
  t = std::isfinite(t) ? std::clamp(t, 0.0, 1.0) : 0.0;
  return map == Colormap::Viridis ? viridis(t) : turbo(t);
}

Points colormap_colors(Colormap map, const VecX& values, double vmin, double vmax) {
  Points C(values.size(), 3);
  const double range = vmax - vmin;
  for (Eigen::Index i = 0; i < values.size(); ++i)
    C.row(i) = colormap_rgb(map, range > 0 ? (values[i] - vmin) / range : 0.0).transpose();
  return C;
}

}  // namespace sflsh::io
