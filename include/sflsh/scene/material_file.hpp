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

/// Writes every region of `materials` under `regions:` with all its keys
/// (young_along, young_through, young_around, poisson, fung_c, density; 17
/// significant digits, so apply_material_file reads back the same doubles),
/// after `comment` lines (each prefixed with "# "). Written as path.partial
/// and renamed: nothing is left at `path` on failure.
void write_material_file(const std::string& path, const std::vector<RegionMaterial>& materials,
                         const std::vector<std::string>& comment = {});

}  // namespace sflsh
