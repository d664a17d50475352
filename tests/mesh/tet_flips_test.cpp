#include <gtest/gtest.h>

#include <set>

#include "sflsh/core/error.hpp"
#include "sflsh/mesh/tet_flips.hpp"
#include "sflsh/mesh/tet_quality.hpp"

namespace sflsh {
namespace {

// Nodes: the triangle (0,0,0), (1,0,0), (0,1,0), then a and e.
Points bipyramid(const Vec3& a, const Vec3& e) {
  Points x(5, 3);
  x << 0, 0, 0, 1, 0, 0, 0, 1, 0, a.x(), a.y(), a.z(), e.x(), e.y(), e.z();
  return x;
}

// The two tets (triangle, a) and (triangle, e) sharing the triangle.
TetMesh two_tets(const Vec3& a, const Vec3& e) {
  TetMesh m;
  m.nodes = bipyramid(a, e);
  m.elements.resize(2, 4);
  m.elements << 0, 1, 2, 3, 0, 1, 2, 4;
  orient_tets_positively(m);
  return m;
}

double volume(const TetMesh& m) {
  double v = 0;
  for (int t = 0; t < m.num_elements(); ++t) v += tet_quality(m, t).signed_volume;
  return v;
}

TEST(TetFlips, TwoThreeFlipReplacesASliverOnAFace) {
  // Apex 2 cm over the triangle: the upper tet is a sliver; the edge a-e crosses the triangle
  // at (0.3, 0.3), inside, so the three tets around a-e fill the same volume, area/3 * (0.02 + 1).
  TetMesh m = two_tets(Vec3(0.3, 0.3, 0.02), Vec3(0.3, 0.3, -1));
  const double before = tet_quality_report(m).min_dihedral_deg;
  std::vector<int> parent;
  const TetFlipReport r = flip_bad_tets(m, 30.0, 4, &parent);
  EXPECT_EQ(r.flips_2_3, 1);
  ASSERT_EQ(m.num_elements(), 3);
  EXPECT_NEAR(volume(m), 0.5 / 3 * 1.02, 1e-12);
  for (int t = 0; t < 3; ++t) {
    EXPECT_GT(tet_quality(m, t).signed_volume, 0);
    const std::set<int> v(m.elements.row(t).data(), m.elements.row(t).data() + 4);
    EXPECT_TRUE(v.count(3) && v.count(4)) << "every new tet holds the edge a-e";
  }
  EXPECT_GT(r.min_dihedral_after, before);
  EXPECT_EQ(parent.size(), 3u);
}

TEST(TetFlips, NoFlipWhenTheEdgeMissesTheFace) {
  // a-e passes outside the triangle (x + y > 1): a 2-3 flip would overlap; nothing changes.
  TetMesh m = two_tets(Vec3(0.9, 0.9, 0.02), Vec3(0.9, 0.9, -1));
  const Tets old = m.elements;
  const TetFlipReport r = flip_bad_tets(m, 30.0);
  EXPECT_EQ(r.flips_2_3 + r.flips_3_2, 0);
  EXPECT_EQ(m.elements, old);
}

TEST(TetFlips, ThreeTwoFlipRemovesALongEdge) {
  // Three tets around a long edge a-e (a 1 m above, e 1 m below the triangle, crossing it near
  // a corner) are worse than the two sharing the triangle: the 3-2 flip makes those two,
  // volume area/3 * 2 kept.
  TetMesh m;
  m.nodes = bipyramid(Vec3(0.05, 0.05, 1), Vec3(0.05, 0.05, -1));
  m.elements.resize(3, 4);
  m.elements << 0, 1, 3, 4, 1, 2, 3, 4, 2, 0, 3, 4;
  orient_tets_positively(m);
  double three = 180;
  for (int t = 0; t < 3; ++t) three = std::min(three, tet_quality(m, t).min_dihedral_deg);
  const TetMesh two = two_tets(Vec3(0.05, 0.05, 1), Vec3(0.05, 0.05, -1));
  ASSERT_GT(tet_quality_report(two).min_dihedral_deg, three);
  const TetFlipReport r = flip_bad_tets(m, 60.0);
  EXPECT_EQ(r.flips_3_2, 1);
  ASSERT_EQ(m.num_elements(), 2);
  EXPECT_NEAR(volume(m), 0.5 / 3 * 2, 1e-12);
  EXPECT_NEAR(r.min_dihedral_after, tet_quality_report(two).min_dihedral_deg, 1e-9);
}

// A kite on the surface z = 0 with perpendicular diagonals q–r (x axis, length 2) and a–b
// (y axis, length 1.05), crossing at the origin, over an inner node i at depth 1: the tets
// (a, q, r, i), (b, q, r, i). a sits 5 cm off q–r, so the surface triangle (a, q, r) is a
// needle (angles ~3, 3, 174 deg) and no position of i could raise its tet.
TetMesh needle_on_the_surface() {
  TetMesh m;
  m.nodes.resize(5, 3);
  m.nodes << 0, 0.05, 0,  // a
      0, -1, 0,           // b
      -1, 0, 0,           // q
      1, 0, 0,            // r
      0, -0.3, -1;        // i
  m.elements.resize(2, 4);
  m.elements << 0, 2, 3, 4, 1, 2, 3, 4;
  orient_tets_positively(m);
  return m;
}

TEST(TetFlips, BoundaryTwoTwoFlipReplacesANeedleSurfaceTriangle) {
  TetMesh m = needle_on_the_surface();
  const double before = tet_quality_report(m).min_dihedral_deg;
  ASSERT_LT(before, 8.0);
  std::vector<int> parent;
  const TetFlipReport r = flip_bad_boundary_edges(m, std::vector<char>(5, 1), 8.0, 4, &parent);
  EXPECT_EQ(r.flips_2_2, 1);
  EXPECT_EQ(r.flips_2_3 + r.flips_3_2, 0);
  ASSERT_EQ(m.num_elements(), 2);
  EXPECT_EQ(parent, (std::vector<int>{0, 0}));
  for (int t = 0; t < 2; ++t) {  // both new tets hold the new edge a-b and the inner node
    std::set<int> v(m.elements.row(t).data(), m.elements.row(t).data() + 4);
    EXPECT_TRUE(v.count(0) && v.count(1) && v.count(4)) << t;
    EXPECT_GT(tet_quality(m, t).signed_volume, 0.0);
  }
  // Coplanar surface nodes: the same pyramid, area 2 * 1.05 / 2 over height 1, volume 0.35.
  EXPECT_NEAR(volume(m), 0.35, 1e-12);
  EXPECT_GT(r.min_dihedral_after, 20.0);
  EXPECT_NEAR(r.min_dihedral_before, before, 1e-12);
}

TEST(TetFlips, BoundaryTwoTwoFlipNeedsSurfaceNodesAndAConvexQuad) {
  TetMesh m = needle_on_the_surface();
  std::vector<char> surface(5, 1);
  surface[1] = 0;  // b off the surface
  EXPECT_EQ(flip_bad_boundary_edges(m, surface, 8.0).flips_2_2, 0);
  // a moved past r along x (still a needle, now beyond r): a-b crosses the x axis at x = 1.43,
  // outside q-r, so the quad a, q, b, r is not convex; q and r lie on one side of the plane
  // (a, b, i) (signed distances -2.55 and -0.45 times |n|, by hand) and the new tets would overlap.
  TetMesh bent = needle_on_the_surface();
  bent.nodes.row(0) << 1.5, 0.05, 0;
  orient_tets_positively(bent);
  ASSERT_LT(tet_quality_report(bent).min_dihedral_deg, 8.0);
  const Tets old = bent.elements;
  EXPECT_EQ(flip_bad_boundary_edges(bent, std::vector<char>(5, 1), 8.0).flips_2_2, 0);
  EXPECT_EQ(bent.elements, old);
  EXPECT_THROW(flip_bad_boundary_edges(m, std::vector<char>(4, 1), 8.0), Error);
}

// The template stage's rule: a flip judged at several body shapes at once. Shape A is the sliver
// of TwoThreeFlipReplacesASliverOnAFace, where the 2-3 flip helps; in shape B the apex a sits
// at (0.9, 0.9, 0.5), so the new edge a-e crosses the plane of the triangle at (0.7, 0.7)
// (by hand: a + (e - a) / 3), outside it: a new tet would be inverted in B (its old two are
// fine there). Judged at A alone the flip is made; at A and B it must be refused.
TEST(TetFlips, AFlipThatHelpsOneShapeButInvertsAnotherIsRefused) {
  const TetMesh a = two_tets(Vec3(0.3, 0.3, 0.02), Vec3(0.3, 0.3, -1));
  Points b = a.nodes;
  b.row(3) << 0.9, 0.9, 0.5;
  ASSERT_GT(tet_quality(TetMesh{b, a.elements}, 0).signed_volume, 0);
  ASSERT_GT(tet_quality(TetMesh{b, a.elements}, 1).signed_volume, 0);
  Tets e = a.elements;
  EXPECT_EQ(flip_bad_tets(e, GeometrySet{a.nodes}, 30.0).flips_2_3, 1);
  EXPECT_EQ(e.rows(), 3);
  e = a.elements;
  const TetFlipReport r = flip_bad_tets(e, GeometrySet{a.nodes, b}, 30.0);
  EXPECT_EQ(r.flips_2_3 + r.flips_3_2, 0);
  EXPECT_EQ(e, a.elements);
  // A shape C where the flip only lowers the angles (a over (0.45, 0.45), still inside the
  // triangle): allowed as long as C stays above the cap, refused with a cap above C's old minimum.
  Points c = a.nodes;
  c.row(3) << 0.45, 0.45, 0.6;
  std::vector<TetNodes> old = {{0, 1, 2, 3}, {0, 1, 2, 4}}, fresh = {{0, 1, 3, 4}, {1, 2, 3, 4}, {2, 0, 3, 4}};
  ASSERT_TRUE(orient_at_reference({a.nodes}, old));
  ASSERT_TRUE(orient_at_reference({a.nodes}, fresh));
  const double old_c = worst_dihedral_deg(c, old), fresh_c = worst_dihedral_deg(c, fresh);
  ASSERT_GT(fresh_c, 5.0);
  ASSERT_LT(fresh_c, old_c) << "the flip lowers C";
  e = a.elements;
  EXPECT_EQ(flip_bad_tets(e, GeometrySet{a.nodes, c}, fresh_c - 1).flips_2_3, 1) << "C stays above the cap";
  e = a.elements;
  EXPECT_EQ(flip_bad_tets(e, GeometrySet{a.nodes, c}, old_c + 1).flips_2_3, 0) << "C would get worse";
}

// The boundary 2-2 flip of the needle, judged with a second shape where a has moved to the
// other side of r (the quad not convex there): the new tets would overlap in that shape.
TEST(TetFlips, BoundaryTwoTwoFlipIsRefusedWhenAnotherShapeMakesTheQuadNonConvex) {
  const TetMesh m = needle_on_the_surface();
  Points bent = m.nodes;
  bent.row(0) << 1.5, 0.05, 0;
  Tets e = m.elements;
  EXPECT_EQ(flip_bad_boundary_edges(e, GeometrySet{m.nodes}, std::vector<char>(5, 1), 8.0).flips_2_2, 1);
  e = m.elements;
  EXPECT_EQ(flip_bad_boundary_edges(e, GeometrySet{m.nodes, bent}, std::vector<char>(5, 1), 8.0).flips_2_2, 0);
  EXPECT_EQ(e, m.elements);
}

}  // namespace
}  // namespace sflsh
