#pragma once
// Farthest-point subsampling, shared by the cubatures that pick a few
// representatives per cell (basis-internal).
#include <vector>

#include "sflsh/core/types.hpp"

namespace sflsh::basis {

/// min(m, #P) row indices of `points` (#P by 3, m ≥ 1): the point nearest the
/// mean first, then repeatedly the point farthest from those chosen
/// (deterministic: ties go to the lowest index).
std::vector<int> farthest_points(const Points& points, int m);

}  // namespace sflsh::basis
