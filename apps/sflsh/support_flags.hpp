#pragma once
// The compact-support flags shared by `precompute` and `bench`:
// --support-radius R (m) and --support-spacing F (× the nearest-handle distance).
#include <string>

#include "sflsh/basis/bounded_biharmonic.hpp"

namespace sflsh::cli {

/// Parses the two flags' texts (empty: not given) into `bbw`; throws one line
/// naming the flag on a bad value or when both are given.
void apply_support_flags(const std::string& radius, const std::string& spacing, basis::BbwOptions& bbw);

}  // namespace sflsh::cli
