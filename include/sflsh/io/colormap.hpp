#pragma once
// Perceptual colour maps for scalar fields on surfaces (displacement, error).
#include <string>

#include "sflsh/core/types.hpp"

namespace sflsh::io {

enum class Colormap {
  Viridis,  ///< matplotlib's viridis (van der Walt & Smith 2015): dark blue -> yellow, perceptually uniform
  Turbo,    ///< Google's turbo (Mikhailov 2019): blue -> red rainbow with smooth lightness
};

/// Parses "viridis" / "turbo" (throws listing the known names).
Colormap colormap_from_name(const std::string& name);

/// RGB in [0, 1] of the map at t (clamped to [0, 1]).
Vec3 colormap_rgb(Colormap map, double t);

/// Per-vertex colours (#V by 3) for `values` (#V) mapped linearly from
/// [vmin, vmax] to [0, 1]; vmax <= vmin gives the colour at 0.
Points colormap_colors(Colormap map, const VecX& values, double vmin, double vmax);

}  // namespace sflsh::io
