#pragma once
// The structure of a PLY file, checked before assimp parses it.
//
// assimp 5.2's PLY reader trusts the header: on a binary file whose body ends before the
// elements the header declares (a truncated download, a damaged file) it reads past the
// buffer and crashes, and on a header without end_header it loops forever (both found by
// scripts/fuzz.sh). check_ply_structure walks the header and, for binary files, every
// element's properties and list counts, so that such a file is one error naming it.

#include <string>
#include <string_view>

namespace sflsh::io {

/// Throws sflsh::Error naming `path` unless `bytes` (the whole file) is a PLY file whose header
/// is complete and, for binary_little_endian / binary_big_endian, whose body holds every
/// element the header declares. Files that do not start with "ply" are not checked (returns).
void check_ply_structure(std::string_view bytes, const std::string& path);

}  // namespace sflsh::io
