#include "sflsh/core/percentile.hpp"

#include <algorithm>
#include <cmath>

namespace sflsh {

double percentile(std::vector<double> v, double p) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const double idx = std::clamp(p, 0.0, 1.0) * double(v.size() - 1);
  const size_t lo = size_t(std::floor(idx)), hi = std::min(v.size() - 1, lo + 1);
  return v[lo] + (idx - double(lo)) * (v[hi] - v[lo]);
}

}  // namespace sflsh
