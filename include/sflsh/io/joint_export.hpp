#pragma once
// Joint positions as a small table people can read or load elsewhere.
#include <string>
#include <vector>

#include "sflsh/core/types.hpp"

namespace sflsh::io {

/// Writes joints (#J by 3, metres) with their names and parents (-1 = root),
/// format from the extension:
///  - .csv:  header "index,name,parent,x,y,z", one joint per line;
///  - .json: {"format_version":1,"units":"metres","joints":[{"index","name",
///           "parent","position":[x,y,z]},...]}.
/// Atomic. Throws naming the path on an unknown extension or mismatched sizes.
void write_joints(const std::string& path, const Points& joints, const std::vector<std::string>& names,
                  const std::vector<int>& parents);

}  // namespace sflsh::io
