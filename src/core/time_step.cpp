#include "sflsh/core/time_step.hpp"

#include <stdexcept>

#include "sflsh/core/error.hpp"

namespace sflsh {

double parse_time_step(const std::string& s, const std::string& what) {
  double v = 0;
  const auto slash = s.find('/');
  try {
    size_t used = 0;
    if (slash == std::string::npos) {
      v = std::stod(s, &used);
      if (used != s.size()) throw std::invalid_argument(s);
    } else {
      size_t u1 = 0, u2 = 0;
      const std::string a = s.substr(0, slash), b = s.substr(slash + 1);
      const double num = std::stod(a, &u1), den = std::stod(b, &u2);
      if (u1 != a.size() || u2 != b.size() || den == 0) throw std::invalid_argument(s);
      v = num / den;
    }
  } catch (const std::exception&) {
    fail(what, ": '", s, "' is not a time step (seconds, e.g. 0.0166 or 1/60)");
  }
  require(v > 0 && v <= 0.1, what, " must be in (0, 0.1] s, got ", v);
  return v;
}

}  // namespace sflsh
