#include "support_flags.hpp"

#include <cmath>
#include <cstdlib>

#include "sflsh/core/error.hpp"

namespace sflsh::cli {

void apply_support_flags(const std::string& radius, const std::string& spacing, basis::BbwOptions& bbw) {
  if (!radius.empty()) {
    char* end = nullptr;
    const double r = std::strtod(radius.c_str(), &end);
    require(end != radius.c_str() && *end == '\0' && std::isfinite(r) && r > 0 && r <= 10,
            "--support-radius must be a length in (0, 10] m, got '", radius, "'");
    bbw.support_radius = r;
  }
  if (!spacing.empty()) {
    char* end = nullptr;
    const double f = std::strtod(spacing.c_str(), &end);
    require(end != spacing.c_str() && *end == '\0' && std::isfinite(f) && f > 0 && f <= 100,
            "--support-spacing must be a factor in (0, 100], got '", spacing, "'");
    require(radius.empty(), "--support-spacing and --support-radius exclude each other");
    bbw.support_spacing_factor = f;
  }
}

}  // namespace sflsh::cli
