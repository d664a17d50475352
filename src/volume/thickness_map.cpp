#include "sflsh/volume/thickness_map.hpp"

#include <cmath>
#include <fstream>
#include <sstream>

#include "sflsh/core/error.hpp"
#include "sflsh/io/input_file.hpp"
#include "sflsh/volume/body_regions.hpp"

namespace sflsh {

double ThicknessMap::scale_of(const std::string& region) const {
  const auto it = scale.find(region);
  return it == scale.end() ? 1.0 : it->second;
}

ThicknessMap ThicknessMap::defaults() {
  ThicknessMap m;
  m.scale = {{"belly", 1.25}, {"buttocks", 1.25}, {"thigh", 1.1}, {"chest", 1.1}};
  return m;
}

ThicknessMap ThicknessMap::uniform() { return ThicknessMap{}; }

ThicknessMap read_thickness_map(const std::string& path) {
  io::require_input_file(path, "thickness map");
  std::ifstream in(path);
  require(bool(in), path, ": cannot open thickness map");
  ThicknessMap map = ThicknessMap::defaults();
  std::string line;
  int lineno = 0, entries = 0;
  while (std::getline(in, line)) {
    ++lineno;
    const auto hash = line.find('#');
    if (hash != std::string::npos) line.erase(hash);
    std::istringstream ls(line);
    std::string region, value, extra;
    if (!(ls >> region)) continue;  // blank or comment
    require(bool(ls >> value), path, ":", lineno, ": expected 'region scale', got only '", region, "'");
    require(!(ls >> extra), path, ":", lineno, ": unexpected '", extra, "' after the scale");
    try {
      body_region_index(region);
    } catch (const Error& e) {
      fail(path, ":", lineno, ": ", e.what());
    }
    double s = 0;
    size_t used = 0;
    try {
      s = std::stod(value, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    require(used == value.size(), path, ":", lineno, ": scale '", value, "' of region ", region,
            " is not a number");
    require(std::isfinite(s) && s > 0 && s <= 3, path, ":", lineno, ": scale ", s, " of region ", region,
            " must be in (0, 3]");
    map.scale[region] = s;
    ++entries;
  }
  // An empty map is a mistake (a wrong or truncated file), not "no change".
  require(entries > 0, path, ": thickness map holds no 'region scale' lines");
  return map;
}

}  // namespace sflsh
