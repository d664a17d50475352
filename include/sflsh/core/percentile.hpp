#pragma once
// Order statistics of timing samples.
#include <vector>

namespace sflsh {

/// The p-quantile (p in [0, 1]) of `values`, linearly interpolated between
/// the order statistics (numpy's default); 0 for no values.
double percentile(std::vector<double> values, double p);

}  // namespace sflsh
