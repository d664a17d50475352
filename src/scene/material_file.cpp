#include "sflsh/scene/material_file.hpp"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "sflsh/core/error.hpp"
#include "sflsh/io/input_file.hpp"

namespace sflsh {
namespace {

std::string where(const std::string& path, const YAML::Node& n) {
  return path + ":" + std::to_string(n.Mark().line + 1);
}

// A map key as text; a key that is itself a list or map is an error.
std::string scalar_key(const std::string& path, const YAML::Node& key) {
  if (!key.IsScalar()) fail(where(path, key), ": expected a plain name as key, got a list or map");
  return key.Scalar();
}

void apply(const std::string& path, const YAML::Node& params, RegionMaterial& m) {
  if (!params.IsMap()) fail(where(path, params), ": expected a map of material parameters for region '", m.name, "'");
  for (const auto& kv : params) {
    const std::string key = scalar_key(path, kv.first);
    double v;
    try {
      v = kv.second.as<double>();
    } catch (const YAML::Exception&) {
      fail(where(path, kv.second), ": '", key, "' must be a number");
    }
    if (!std::isfinite(v)) fail(where(path, kv.second), ": '", key, "' must be finite");
    auto positive = [&](double& slot) {
      if (v <= 0) fail(where(path, kv.second), ": '", key, "' must be positive, got ", v);
      slot = v;
    };
    if (key == "young") {
      positive(m.young_along);
      m.young_through = m.young_around = v;
    } else if (key == "young_along") positive(m.young_along);
    else if (key == "young_through") positive(m.young_through);
    else if (key == "young_around") positive(m.young_around);
    else if (key == "fung_c") positive(m.fung_c);
    else if (key == "density") positive(m.density);
    else if (key == "poisson") {
      if (v <= -1.0 || v >= 0.5) fail(where(path, kv.second), ": 'poisson' must be in (-1, 0.5), got ", v);
      m.poisson = v;
    } else {
      fail(where(path, kv.first), ": unknown material key '", key,
           "' (expected young, young_along, young_through, young_around, poisson, fung_c, density)");
    }
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
      if (!kv.second.IsMap()) fail(where(path, kv.second), ": 'regions' must map region names to parameters");
      for (const auto& r : kv.second) {
        const std::string name = scalar_key(path, r.first);
        auto it = std::find_if(materials.begin(), materials.end(), [&](const RegionMaterial& m) { return m.name == name; });
        if (it == materials.end()) {
          std::string known;
          for (const auto& m : materials) known += (known.empty() ? "" : ", ") + m.name;
          fail(where(path, r.first), ": unknown region '", name, "' (this avatar has: ", known, ")");
        }
        apply(path, r.second, *it);
      }
    } else {
      fail(where(path, kv.first), ": unknown top-level key '", key, "' (expected 'all' or 'regions')");
    }
  }
}

YAML::Node load_yaml(const std::string& name, const std::string& text) {
  try {
    return YAML::Load(text);
  } catch (const YAML::Exception& e) {
    fail(name, ":", e.mark.line + 1, ": malformed YAML: ", e.msg);
  }
}

}  // namespace

void apply_material_file(const std::string& path, std::vector<RegionMaterial>& materials) {
  io::require_input_file(path, "material file");
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  if (!in) fail(path, ": cannot read the material file");
  apply_material_text(text.str(), path, materials);
}

void apply_material_text(const std::string& text, const std::string& name, std::vector<RegionMaterial>& materials) {
  apply_root(name, load_yaml(name, text), materials);
}

void write_material_file(const std::string& path, const std::vector<RegionMaterial>& materials,
                         const std::vector<std::string>& comment) {
  const std::string partial = path + ".partial";
  {
    std::ofstream f(partial);
    if (!f) fail(path, ": cannot write the material file");
    f.precision(17);
    for (const std::string& c : comment) f << "# " << c << "\n";
    f << "regions:\n";
    for (const RegionMaterial& m : materials)
      f << "  " << m.name << ": {young_along: " << m.young_along << ", young_through: " << m.young_through
        << ", young_around: " << m.young_around << ", poisson: " << m.poisson << ", fung_c: " << m.fung_c
        << ", density: " << m.density << "}\n";
    f.close();
    if (!f) {
      std::filesystem::remove(partial);
      fail(path, ": write failed");
    }
  }
  std::filesystem::rename(partial, path);
}

}  // namespace sflsh
