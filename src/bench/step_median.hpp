#pragma once
// The step-time median the contact benchmarks report: over the steps with
// contact, or over every step when there is none.
#include <vector>

#include "sflsh/core/percentile.hpp"

namespace sflsh {

/// Median of `ms` over the steps flagged in `when` (all steps if none is).
inline double median_when(const std::vector<double>& ms, const std::vector<bool>& when) {
  std::vector<double> picked;
  for (size_t i = 0; i < ms.size() && i < when.size(); ++i)
    if (when[i]) picked.push_back(ms[i]);
  return percentile(picked.empty() ? ms : picked, 0.5);
}

}  // namespace sflsh
