#pragma once
// Spatially varying skin thickness (seed §4): a scale factor per body region
// applied to the soft layer between the inner (bone) surface and the skin.
#include <map>
#include <string>

namespace sflsh {

struct ThicknessMap {
  /// Region name (see body_region_names()) -> scale of the soft-layer
  /// thickness; regions not listed use 1.
  std::map<std::string, double> scale;

  double scale_of(const std::string& region) const;

  /// The default: belly and buttocks 1.25, thighs 1.1, chest 1.1 (where fat
  /// accumulates), everything else 1.
  static ThicknessMap defaults();
  /// All regions 1 (the template's medium thickness everywhere).
  static ThicknessMap uniform();
};

/// Reads a thickness map: one "region scale" pair per line, '#' starts a
/// comment, blank lines ignored; scales must be finite and in (0, 3]. Regions
/// not listed keep the default from ThicknessMap::defaults(). Throws
/// sflsh::Error naming the file, line and what was expected.
ThicknessMap read_thickness_map(const std::string& path);

}  // namespace sflsh
