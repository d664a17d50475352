#pragma once
// Checks on an input file before it is read, so that a typo or a folder given
// where a file is expected is one clear error naming the option and the path
// (std::ifstream opens a folder without complaint on Linux and then reads
// nothing, which a text reader would take for an empty file).
#include <string>

namespace sflsh::io {

/// Throws "WHAT PATH: file not found" / ": is a folder, expected a file" /
/// ": cannot be read" unless `path` is a readable regular file (or a symlink
/// to one). `what` names the option or the kind of file ("--material",
/// "joint map"); it may be empty.
void require_input_file(const std::string& path, const std::string& what);

}  // namespace sflsh::io
