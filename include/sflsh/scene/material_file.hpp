#pragma once
// Material overrides from a YAML file (`sflsh simulate --material FILE`):
//
//   all:                      # optional: applied to every region first
//     young: 2.0e4            # Pa, sets young_along/through/around at once
//     poisson: 0.45
//   regions:
//     belly: {young_along: 1.0e4, young_through: 5.0e3, young_around: 8.0e3, fung_c: 1.0e3}
//     thigh: {young: 3.0e4, density: 1050}
//
// Keys: young, young_along, young_through, young_around (Pa), poisson, fung_c
// (Pa), density (kg/m^3). Unknown regions or keys and out-of-range values are
// errors naming the file, the line and the key.
#include <string>
#include <vector>

#include "sflsh/asset/avatar.hpp"

namespace sflsh {

/// Applies the overrides in `path` to `materials` (by region name).
void apply_material_file(const std::string& path, std::vector<RegionMaterial>& materials);
/// The same for YAML `text` in memory; `name` stands for the file in errors.
void apply_material_text(const std::string& text, const std::string& name, std::vector<RegionMaterial>& materials);

}  // namespace sflsh
