// The range of a region's material parameters (RegionMaterial, avatar.hpp).
#include <sstream>

#include "sflsh/asset/avatar.hpp"
#include "sflsh/core/error.hpp"

namespace sflsh {

std::string RegionMaterial::range_problem() const {
  std::ostringstream o;
  if (!(young_along > 0 && young_through > 0 && young_around > 0))
    o << "Young's moduli must be > 0 (got " << young_along << ", " << young_through << ", " << young_around << ")";
  else if (!(poisson > -1.0 && poisson < 0.5))
    o << "poisson = " << poisson << ", expected in (-1, 0.5)";
  else if (!(fung_c > 0))
    o << "fung_c = " << fung_c << ", expected > 0";
  else if (!(density > 0))
    o << "density = " << density << ", expected > 0";
  return o.str();
}

void RegionMaterial::require_in_range() const {
  const std::string problem = range_problem();
  if (!problem.empty()) fail("material '", name, "': ", problem);
}

}  // namespace sflsh
