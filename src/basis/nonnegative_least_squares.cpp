#include "nonnegative_least_squares.hpp"

#include <algorithm>
#include <cmath>

namespace sflsh::basis {

int nonnegative_least_squares(const MatX& Q, const VecX& f, VecX& c, int max_sweeps) {
  const Eigen::Index n = c.size();
  VecX g = Q * c - f;  // gradient, updated incrementally
  int sweep = 0;
  for (; sweep < max_sweeps; ++sweep) {
    double change = 0;
    for (Eigen::Index s = 0; s < n; ++s) {
      if (Q(s, s) <= 0) continue;
      const double next = std::max(0.0, c[s] - g[s] / Q(s, s));
      const double delta = next - c[s];
      if (delta == 0) continue;
      c[s] = next;
      g += delta * Q.col(s);
      change = std::max(change, std::abs(delta));
    }
    if (change <= 1e-10 * c.maxCoeff()) break;
  }
  return sweep;
}

}  // namespace sflsh::basis
