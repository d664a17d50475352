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

// Two tets (a, c, d, e), (b, c, d, e) sharing face (c, d, e), and an ear (a, c, d, p) on the
// boundary face (a, c, d): p at height s over the face's centroid, on its outer side (normal
// (−1, −1, 1)/√3 by hand, e below it), so the ear's volume is s·|face|/3 and it is flat for
// small s. p is node 2, so the nodes after it move down by one. (b, c, d, e) is an ear too,
// around b, but a good one.
TetMesh mesh_with_ear(double s) {
  TetMesh m;
  const Vec3 a(0, 0, 0), c(1, 0, 1), d(0, 1, 1), n = Vec3(-1, -1, 1).normalized();
  const Vec3 p = (a + c + d) / 3 + s * n;
  m.nodes.resize(6, 3);
  m.nodes << a.transpose(), c.transpose(), p.transpose(), d.transpose(), 0.5, 0.5, -1, 1, 1, 0;
  m.elements.resize(3, 4);
  m.elements << 0, 1, 3, 4,  // a c d e
      5, 1, 3, 4,            // b c d e
      0, 1, 3, 2;            // a c d p: the ear
  orient_tets_positively(m);
  return m;
}

TEST(BoundaryEars, RemovesAFlatEarWithItsApexAndRenumbersTheNodes) {
  TetMesh m = mesh_with_ear(0.01);
  const double face_area = 0.5 * Vec3(1, 0, 1).cross(Vec3(0, 1, 1)).norm();  // √3/2
  EXPECT_NEAR(std::abs(tet_quality(m, 2).signed_volume), 0.01 * face_area / 3, 1e-12);
  ASSERT_LT(tet_quality(m, 2).min_dihedral_deg, 8.0);
  ASSERT_GT(tet_quality(m, 1).min_dihedral_deg, 8.0);
  const TetMesh before = m;
  std::vector<int> kept_tets, kept_nodes;
  const BoundaryCapReport r = remove_bad_boundary_ears(m, std::vector<char>(6, 1), 8.0, &kept_tets, &kept_nodes);
  EXPECT_EQ(r.removed, 1);
  EXPECT_EQ(r.kept_bad, 0);
  EXPECT_EQ(kept_tets, (std::vector<int>{0, 1}));
  EXPECT_EQ(kept_nodes, (std::vector<int>{0, 1, 3, 4, 5}));
  ASSERT_EQ(m.num_nodes(), 5);
  ASSERT_EQ(m.num_elements(), 2);
  // Same tets, same points: every corner of the output is the input's corner moved to its new index.
  for (int t = 0; t < 2; ++t)
    for (int k = 0; k < 4; ++k)
      EXPECT_EQ(m.nodes.row(m.elements(t, k)), before.nodes.row(before.elements(t, k))) << t << " " << k;
  EXPECT_EQ(m.elements.maxCoeff(), 4);
  EXPECT_EQ(tet_quality_report(m).num_inverted, 0);
}

TEST(BoundaryEars, KeepsGoodEarsEarsOffTheSurfaceAndPinchedApexes) {
  TetMesh good = mesh_with_ear(0.5);
  ASSERT_GT(tet_quality(good, 2).min_dihedral_deg, 8.0);
  EXPECT_EQ(remove_bad_boundary_ears(good, std::vector<char>(6, 1), 8.0).removed, 0);
  EXPECT_EQ(good.num_nodes(), 6);

  TetMesh off = mesh_with_ear(0.01);
  std::vector<char> surface(6, 1);
  surface[2] = 0;  // the apex is not on the surface
  EXPECT_EQ(remove_bad_boundary_ears(off, surface, 8.0).removed, 0);

  // The apex also in a tet of its own above it (a pinched vertex): it cannot go, so neither can the ear.
  TetMesh pinched = mesh_with_ear(0.01);
  const Vec3 p = pinched.nodes.row(2).transpose();
  pinched.nodes.conservativeResize(9, 3);
  pinched.nodes.row(6) = (p + Vec3(1, 0, 2)).transpose();
  pinched.nodes.row(7) = (p + Vec3(0, 1, 2)).transpose();
  pinched.nodes.row(8) = (p + Vec3(0, 0, 3)).transpose();
  pinched.elements.conservativeResize(4, 4);
  pinched.elements.row(3) << 2, 6, 7, 8;
  orient_tets_positively(pinched);
  const BoundaryCapReport r = remove_bad_boundary_ears(pinched, std::vector<char>(9, 1), 8.0);
  EXPECT_EQ(r.removed, 0);
  EXPECT_EQ(r.kept_bad, 1);
  EXPECT_EQ(pinched.num_nodes(), 9);
  EXPECT_THROW(remove_bad_boundary_ears(pinched, std::vector<char>(3, 1), 8.0), Error);
}

// Judged at several shapes: a cap that is good in the reference geometry (h = 1) but inverted
// in another shape (c, d pushed below the diagonal) goes, and the reference keeps no inverted tet.
TEST(BoundaryCaps, ACapBadInOneShapeGoesWhenJudgedOverAllShapes) {
  const TetMesh good = roof(1.0);
  Points concave = good.nodes;
  concave(2, 2) = concave(3, 2) = -0.05;
  Tets e = good.elements;
  EXPECT_EQ(remove_bad_boundary_caps(e, GeometrySet{good.nodes}, std::vector<char>(5, 1), 8.0).removed, 0);
  std::vector<int> kept;
  EXPECT_EQ(remove_bad_boundary_caps(e, GeometrySet{good.nodes, concave}, std::vector<char>(5, 1), 8.0, &kept).removed,
            1);
  EXPECT_EQ(kept, (std::vector<int>{1, 2}));
  EXPECT_EQ(tet_quality_report(TetMesh{good.nodes, e}).num_inverted, 0);
  EXPECT_EQ(tet_quality_report(TetMesh{concave, e}).num_inverted, 0);
}

// An ear that is fine in the reference geometry and flat in another shape goes with its apex;
// the tets are renumbered, the geometries are left to the caller (kept_nodes).
TEST(BoundaryEars, AnEarFlatInOneShapeGoesWhenJudgedOverAllShapes) {
  const TetMesh good = mesh_with_ear(0.5), flat = mesh_with_ear(0.01);
  Tets e = good.elements;
  std::vector<int> kept_tets, kept_nodes;
  EXPECT_EQ(remove_bad_boundary_ears(e, GeometrySet{good.nodes}, std::vector<char>(6, 1), 8.0).removed, 0);
  const BoundaryCapReport r = remove_bad_boundary_ears(e, GeometrySet{good.nodes, flat.nodes}, std::vector<char>(6, 1),
                                                       8.0, &kept_tets, &kept_nodes);
  EXPECT_EQ(r.removed, 1);
  EXPECT_EQ(kept_tets, (std::vector<int>{0, 1}));
  EXPECT_EQ(kept_nodes, (std::vector<int>{0, 1, 3, 4, 5}));
  EXPECT_EQ(e.rows(), 2);
  EXPECT_EQ(e.maxCoeff(), 4);
}

}  // namespace
}  // namespace sflsh
