#include "sflsh/scene/material_file.hpp"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "sflsh/core/error.hpp"
#include "sflsh/io/input_file.hpp"
#include "sflsh/io/atomic_output.hpp"
#include "sflsh/scene/yaml_document.hpp"

namespace sflsh {
namespace {

// A map key as text; a key that is itself a list or map is an error.
std::string scalar_key(const std::string& path, const YAML::Node& key) {
  if (!key.IsScalar()) fail(yaml_where(path, key), ": expected a plain name as key, got a list or map");
  return key.Scalar();
}

void apply(const std::string& path, const YAML::Node& params, RegionMaterial& m) {
  if (!params.IsMap()) fail(yaml_where(path, params), ": expected a map of material parameters for region '", m.name, "'");
  for (const auto& kv : params) {
    const std::string key = scalar_key(path, kv.first);
    double v;
    try {
      v = kv.second.as<double>();
    } catch (const YAML::Exception&) {
      fail(yaml_where(path, kv.second), ": '", key, "' must be a number");
    }
    if (!std::isfinite(v)) fail(yaml_where(path, kv.second), ": '", key, "' must be finite");
    if (key == "young") m.young_along = m.young_through = m.young_around = v;
    else if (key == "young_along") m.young_along = v;
    else if (key == "young_through") m.young_through = v;
    else if (key == "young_around") m.young_around = v;
    else if (key == "fung_c") m.fung_c = v;
    else if (key == "density") m.density = v;
    else if (key == "poisson") m.poisson = v;
    else
      fail(yaml_where(path, kv.first), ": unknown material key '", key,
           "' (expected young, young_along, young_through, young_around, poisson, fung_c, density)");
    // The region was in range before this key: what is out of range now is its value.
    const std::string problem = m.range_problem();
    if (!problem.empty()) fail(yaml_where(path, kv.second), ": '", key, "' of region '", m.name, "': ", problem);
  }
}

}  // namespace

namespace {

void apply_root(const std::string& path, const YAML::Node& root, std::vector<RegionMaterial>& materials) {
  if (!root.IsMap()) fail(path, ": expected a map with 'all' and/or 'regions'");
  for (const auto& kv : root) {
    const std::string key = scalar_key(path, kv.first);
    if (key == "all") {
      for (auto& m : materials) apply(path, kv.second, m);
    } else if (key == "regions") {
      if (!kv.second.IsMap()) fail(yaml_where(path, kv.second), ": 'regions' must map region names to parameters");
      for (const auto& r : kv.second) {
        const std::string name = scalar_key(path, r.first);
        auto it = std::find_if(materials.begin(), materials.end(), [&](const RegionMaterial& m) { return m.name == name; });
        if (it == materials.end()) {
          std::string known;
          for (const auto& m : materials) known += (known.empty() ? "" : ", ") + m.name;
          fail(yaml_where(path, r.first), ": unknown region '", name, "' (this avatar has: ", known, ")");
        }
        apply(path, r.second, *it);
      }
    } else {
      fail(yaml_where(path, kv.first), ": unknown top-level key '", key, "' (expected 'all' or 'regions')");
    }
  }
}

}  // namespace

void apply_material_file(const std::string& path, std::vector<RegionMaterial>& materials) {
  apply_root(path, load_yaml_file(path, "material file"), materials);
}

void apply_material_text(const std::string& text, const std::string& name, std::vector<RegionMaterial>& materials) {
  apply_root(name, load_yaml_text(text, name), materials);
}

void write_material_file(const std::string& path, const std::vector<RegionMaterial>& materials,
                         const std::vector<std::string>& comment) {
  io::write_text_file(path, [&](std::ostream& f) {
    f.precision(17);
    for (const std::string& c : comment) f << "# " << c << "\n";
    f << "regions:\n";
    for (const RegionMaterial& m : materials)
      f << "  " << m.name << ": {young_along: " << m.young_along << ", young_through: " << m.young_through
        << ", young_around: " << m.young_around << ", poisson: " << m.poisson << ", fung_c: " << m.fung_c
        << ", density: " << m.density << "}\n";
  });
}

}  // namespace sflsh
