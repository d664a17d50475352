#include <gtest/gtest.h>

#include <set>

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

}  // namespace
}  // namespace sflsh
