#pragma once
// Non-negative least squares on the normal equations (basis-internal; the
// fitted cubatures' weight solve).
#include "sflsh/core/types.hpp"

namespace sflsh::basis {

/// Minimizes ½ cᵀQc − fᵀc subject to c ≥ 0 (Q = AᵀA symmetric PSD, n by n;
/// f = Aᵀb) by cyclic projected coordinate descent from `c` (n, ≥ 0), which
/// holds the solution on return. Stops when a sweep changes no weight by more
/// than 1e-10 · max c, or after `max_sweeps`; returns the sweeps done.
int nonnegative_least_squares(const MatX& Q, const VecX& f, VecX& c, int max_sweeps = 2000);

}  // namespace sflsh::basis
