#pragma once
// Time steps as people write them: "1/60", "0.0166".
#include <string>

namespace sflsh {

/// Seconds from "N/D" or a decimal; throws naming `what` (e.g. "--dt") when
/// the text is not a number or the step is outside (0, 0.1] s.
double parse_time_step(const std::string& text, const std::string& what = "--dt");

}  // namespace sflsh
