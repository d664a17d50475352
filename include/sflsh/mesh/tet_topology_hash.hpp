#pragma once
// A content key of a tet connectivity (the element array alone, not the
// nodes): equal for every avatar of one body model and template stage, since
// every body shape uses the same tets (seed §4); a batch checks its outputs
// against it.
#include <string>

#include "sflsh/core/types.hpp"

namespace sflsh {

/// 16 lower-case hex digits: 64-bit FNV-1a over the bytes of `elements`
/// (#T by 4) as little-endian int32 in row-major order (tet 0's four nodes,
/// then tet 1's, ...). Equal arrays give equal keys; a changed index or order
/// changes it.
std::string tet_topology_hash(const Tets& elements);

}  // namespace sflsh
