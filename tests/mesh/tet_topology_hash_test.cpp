#include <gtest/gtest.h>

#include "sflsh/mesh/tet_topology_hash.hpp"

namespace sflsh {
namespace {

// Values computed independently in Python: FNV-1a 64 with core/fnv_hash.cpp's offset basis
// 1469598103934665603 and prime 1099511628211 over struct.pack('<8i', ...).
TEST(TetTopologyHash, KnownValuesAndSensitivityToOrder) {
  Tets e(2, 4);
  e << 0, 1, 2, 3, 1, 2, 3, 4;
  EXPECT_EQ(tet_topology_hash(e), "bce77c5e4a7564c7");
  Tets swapped(2, 4);
  swapped << 1, 2, 3, 4, 0, 1, 2, 3;
  EXPECT_EQ(tet_topology_hash(swapped), "0da1d915369755c7");
  EXPECT_EQ(tet_topology_hash(Tets(0, 4)), "14650fb0739d0383");  // no bytes: the offset basis
}

}  // namespace
}  // namespace sflsh
