#include <gtest/gtest.h>

#include <cmath>

#include "sflsh/mesh/geometry_set.hpp"

namespace sflsh {
namespace {

// The corner tet (origin and the three unit points): dihedral angles 90 deg at the three edges
// through the origin and arccos(1/sqrt(3)) = 54.7356 deg at the other three (by hand: the
// face normals (0,0,-1) and (1,1,1)/sqrt(3) make arccos(1/sqrt(3)) with the interior angle).
Points corner(double apex_z) {
  Points x(4, 3);
  x << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, apex_z;
  return x;
}

TEST(GeometrySet, WorstDihedralOfKnownTetsAndInvertedOnes) {
  const std::vector<TetNodes> t = {{0, 1, 2, 3}};
  EXPECT_NEAR(worst_dihedral_deg(corner(1), t), std::acos(1 / std::sqrt(3.0)) * 180 / M_PI, 1e-9);
  EXPECT_EQ(worst_dihedral_deg(corner(-1), t), -1.0);  // apex below: negative orientation
  EXPECT_EQ(worst_dihedral_deg(corner(1), {}), 180.0);
  // Flattened apex at z = 0.01: the dihedral at the edge (1,2) is atan(0.01 * sqrt(2)) = 0.81 deg.
  EXPECT_NEAR(worst_dihedral_deg(corner(0.01), t), std::atan(0.01 * std::sqrt(2.0)) * 180 / M_PI, 1e-9);
}

TEST(GeometrySet, AReplacementMustHelpOneGeometryAndSpoilNone) {
  // Nodes 0-3: a corner tet whose apex (node 3) is at z = 1 in geometry "good" and at z = 0.01
  // in "flat"; node 4 is the apex at z = 1 in both. old = (0,1,2,3), fresh = (0,1,2,4).
  Points good(5, 3), flat(5, 3);
  good << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 1;
  flat = good;
  flat(3, 2) = 0.01;
  const std::vector<TetNodes> old = {{0, 1, 2, 3}}, fresh = {{0, 1, 2, 4}};
  EXPECT_TRUE(replacement_accepted({good, flat}, fresh, old, 10.0)) << "helps flat, equal at good";
  EXPECT_FALSE(replacement_accepted({good}, fresh, old, 10.0)) << "equal everywhere: no help";
  // A third geometry where node 4 is below the base: the fresh tet inverts there.
  Points below = good;
  below(4, 2) = -0.5;
  EXPECT_FALSE(replacement_accepted({good, flat, below}, fresh, old, 10.0)) << "inverts one geometry";
  // A geometry where fresh is worse than old but both stay above the cap: still accepted; with a
  // cap above both, the drop counts and the replacement is refused.
  Points lower = good;
  lower(4, 0) = 0.6, lower(4, 1) = 0.6, lower(4, 2) = 0.5;  // a fresh tet worse than the corner tet
  const double old_deg = worst_dihedral_deg(lower, old), fresh_deg = worst_dihedral_deg(lower, fresh);
  ASSERT_GT(fresh_deg, 10.0);
  ASSERT_LT(fresh_deg, old_deg);
  EXPECT_TRUE(replacement_accepted({good, flat, lower}, fresh, old, 10.0));
  EXPECT_FALSE(replacement_accepted({good, flat, lower}, fresh, old, 60.0));
  // A removal (no fresh tets) helps only where the old tet is below the cap or inverted.
  EXPECT_TRUE(replacement_accepted({good, flat}, {}, old, 8.0));
  EXPECT_FALSE(replacement_accepted({good}, {}, old, 8.0));
}

TEST(GeometrySet, OrientsAtTheReferenceGeometryOnly) {
  Points ref = corner(1), other = corner(-1);
  std::vector<TetNodes> t = {{0, 1, 3, 2}};  // negative at ref
  ASSERT_TRUE(orient_at_reference({ref, other}, t));
  EXPECT_EQ(t[0], (TetNodes{0, 1, 2, 3}));
  EXPECT_GT(worst_dihedral_deg(ref, t), 0);
  EXPECT_EQ(worst_dihedral_deg(other, t), -1.0) << "the orientation is the reference's, not each geometry's";
  std::vector<TetNodes> flat = {{0, 1, 2, 3}};
  EXPECT_FALSE(orient_at_reference({corner(0)}, flat));
}

}  // namespace
}  // namespace sflsh
