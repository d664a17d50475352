#include <gtest/gtest.h>

#include "sflsh/core/error.hpp"
#include "sflsh/mesh/boundary_caps.hpp"
#include "sflsh/mesh/tet_quality.hpp"

namespace sflsh {
namespace {

// A cap (a, b, c, d) on top of two tets (a, c, d, e), (b, c, d, e): the cap's faces (a, b, c),
// (a, b, d) are on the boundary and share the diagonal a-b of the unit square; c and d sit at
// height h over the other diagonal's ends, e below. The cap's volume is h/3 (det of b-a, c-a,
// d-a = -2h, by hand), so it is flat for small h.
TetMesh roof(double h) {
  TetMesh m;
  m.nodes.resize(5, 3);
  m.nodes << 0, 0, 0,  // a
      1, 1, 0,         // b
      1, 0, h,         // c
      0, 1, h,         // d
      0.5, 0.5, -1;    // e
  m.elements.resize(3, 4);
  m.elements << 0, 1, 2, 3, 0, 2, 3, 4, 1, 2, 3, 4;
  orient_tets_positively(m);
  return m;
}

TEST(BoundaryCaps, RemovesAFlatCapAndKeepsTheRest) {
  TetMesh m = roof(0.01);
  EXPECT_NEAR(std::abs(tet_quality(m, 0).signed_volume), 0.01 / 3, 1e-12);
  ASSERT_LT(tet_quality(m, 0).min_dihedral_deg, 8.0);
  std::vector<int> kept;
  const BoundaryCapReport r = remove_bad_boundary_caps(m, std::vector<char>(5, 1), 8.0, &kept);
  EXPECT_EQ(r.removed, 1);
  EXPECT_EQ(r.kept_bad, 0);
  ASSERT_EQ(m.num_elements(), 2);
  EXPECT_EQ(kept, (std::vector<int>{1, 2}));
  for (int t = 0; t < 2; ++t)  // the two lower tets, nodes unchanged
    EXPECT_TRUE((m.elements.row(t).array() == 4).any());
  EXPECT_EQ(m.nodes(2, 2), 0.01);
}

TEST(BoundaryCaps, RemovesAnInvertedCap) {
  TetMesh m = roof(0.2);
  m.nodes(2, 2) = m.nodes(3, 2) = -0.05;  // c, d pushed below the a-b diagonal: the ridge turned concave
  ASSERT_LE(tet_quality(m, 0).signed_volume, 0.0);
  EXPECT_EQ(remove_bad_boundary_caps(m, std::vector<char>(5, 1), 8.0).removed, 1);
  EXPECT_EQ(tet_quality_report(m).num_inverted, 0);
}

TEST(BoundaryCaps, KeepsGoodCapsCapsOffTheSurfaceAndLoneTets) {
  TetMesh m = roof(1.0);
  ASSERT_GT(tet_quality(m, 0).min_dihedral_deg, 8.0);
  EXPECT_EQ(remove_bad_boundary_caps(m, std::vector<char>(5, 1), 8.0).removed, 0);
  TetMesh flat = roof(0.01);
  std::vector<char> surface(5, 1);
  surface[2] = 0;  // c not on the surface
  EXPECT_EQ(remove_bad_boundary_caps(flat, surface, 8.0).removed, 0);
  // A single flat tet has four boundary faces: removing it would orphan its nodes.
  TetMesh lone = roof(0.01);
  lone.elements.conservativeResize(1, 4);
  const BoundaryCapReport r = remove_bad_boundary_caps(lone, std::vector<char>(5, 1), 8.0);
  EXPECT_EQ(r.removed, 0);
  EXPECT_EQ(r.kept_bad, 1);
  EXPECT_THROW(remove_bad_boundary_caps(lone, std::vector<char>(4, 1), 8.0), Error);
}

}  // namespace
}  // namespace sflsh
