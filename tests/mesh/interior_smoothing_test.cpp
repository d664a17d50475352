#include <gtest/gtest.h>

#include <random>

#include "sflsh/core/error.hpp"
#include "sflsh/mesh/interior_smoothing.hpp"
#include "sflsh/mesh/tet_quality.hpp"

namespace sflsh {
namespace {

// Unit cube split into 12 tets: each side's two triangles joined to an inner node 8 at `c`.
TetMesh cube_with_inner_node(const Vec3& c) {
  TetMesh m;
  m.nodes.resize(9, 3);
  for (int i = 0; i < 8; ++i) m.nodes.row(i) << (i & 1), (i >> 1) & 1, (i >> 2) & 1;
  m.nodes.row(8) = c.transpose();
  const int quads[6][4] = {{0, 1, 3, 2}, {4, 6, 7, 5}, {0, 4, 5, 1}, {2, 3, 7, 6}, {0, 2, 6, 4}, {1, 5, 7, 3}};
  m.elements.resize(12, 4);
  for (int q = 0; q < 6; ++q) {
    m.elements.row(2 * q) << quads[q][0], quads[q][1], quads[q][2], 8;
    m.elements.row(2 * q + 1) << quads[q][0], quads[q][2], quads[q][3], 8;
  }
  // Orient by the centred configuration, so a node pushed through a side gives inverted tets.
  TetMesh centred = m;
  centred.nodes.row(8) << 0.5, 0.5, 0.5;
  for (int t = 0; t < 12; ++t)
    if (tet_quality(centred, t).signed_volume < 0) std::swap(m.elements(t, 2), m.elements(t, 3));
  return m;
}

std::vector<NodeFreedom> only_inner(NodeFreedom f) {
  std::vector<NodeFreedom> v(9, NodeFreedom::Fixed);
  v[8] = f;
  return v;
}

TEST(InteriorSmoothing, RaisesAKnownBadDihedralTowardsTheCentredMesh) {
  // With the inner node at the centre every tet has its smallest angle at the value below
  // (by symmetry the best the inner node can do); 1 cm above the bottom the two bottom tets are
  // slivers.
  const double centred = tet_quality_report(cube_with_inner_node(Vec3(0.5, 0.5, 0.5))).min_dihedral_deg;
  TetMesh m = cube_with_inner_node(Vec3(0.5, 0.5, 0.01));
  const Points corners = m.nodes.topRows(8);
  const double before = tet_quality_report(m).min_dihedral_deg;
  ASSERT_LT(before, 2.0);
  InteriorSmoothingOptions o;
  o.target_deg = 80.0;  // keep improving
  o.passes = 200;
  o.max_displacement_fraction = 2.0;
  const InteriorSmoothingReport r = smooth_interior_nodes(m, only_inner(NodeFreedom::Free), Points(), o);
  const TetQualityReport q = tet_quality_report(m);
  EXPECT_NEAR(r.min_dihedral_before, before, 1e-12);
  EXPECT_NEAR(r.min_dihedral_after, q.min_dihedral_deg, 1e-12);
  EXPECT_EQ(q.num_inverted, 0);
  EXPECT_GT(q.min_dihedral_deg, 0.95 * centred) << "centred: " << centred;
  EXPECT_LE(q.min_dihedral_deg, centred + 1e-9);
  EXPECT_LT((m.nodes.row(8) - Eigen::RowVector3d(0.5, 0.5, 0.5)).norm(), 0.05);
  EXPECT_EQ(m.nodes.topRows(8), corners) << "fixed nodes moved";
  EXPECT_GT(r.moves, 0);
  EXPECT_EQ(r.nodes_moved, 1);
}

TEST(InteriorSmoothing, SlidingNodeStaysInItsPlane) {
  TetMesh m = cube_with_inner_node(Vec3(0.03, 0.5, 0.37));
  Points normals = Points::Zero(9, 3);
  normals.row(8) << 0, 0, 1;  // may move in x and y only
  InteriorSmoothingOptions o;
  o.target_deg = 80.0;
  o.passes = 200;
  o.max_displacement_fraction = 2.0;
  const double before = tet_quality_report(m).min_dihedral_deg;
  smooth_interior_nodes(m, only_inner(NodeFreedom::Slide), normals, o);
  EXPECT_DOUBLE_EQ(m.nodes(8, 2), 0.37);
  EXPECT_NEAR(m.nodes(8, 0), 0.5, 0.05);
  EXPECT_NEAR(m.nodes(8, 1), 0.5, 0.05);
  EXPECT_GT(tet_quality_report(m).min_dihedral_deg, before + 5.0);
}

TEST(InteriorSmoothing, UninvertsAndNeverInvertsOrLowersTheMinimum) {
  // Pushed through the bottom: the two bottom tets are inverted and get fixed.
  TetMesh m = cube_with_inner_node(Vec3(0.4, 0.6, -0.05));
  ASSERT_EQ(tet_quality_report(m).num_inverted, 2);
  InteriorSmoothingOptions o;
  o.max_displacement_fraction = 2.0;
  InteriorSmoothingReport r = smooth_interior_nodes(m, only_inner(NodeFreedom::Free), Points(), o);
  EXPECT_EQ(r.inverted_before, 2);
  EXPECT_EQ(r.inverted_after, 0);
  EXPECT_EQ(tet_quality_report(m).num_inverted, 0);
  // Random inner positions, targets and displacement limits: never an inverted tet, never a lower
  // minimum, and the limit is respected.
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> U(0.02, 0.98), T(5.0, 60.0), L(0.05, 1.0);
  for (int trial = 0; trial < 50; ++trial) {
    const Vec3 c(U(rng), U(rng), U(rng));
    TetMesh k = cube_with_inner_node(c);
    const TetQualityReport q0 = tet_quality_report(k);
    ASSERT_EQ(q0.num_inverted, 0);
    InteriorSmoothingOptions ok;
    ok.target_deg = T(rng);
    ok.max_displacement_fraction = L(rng);
    double shortest = 1e9;
    for (int i = 0; i < 8; ++i) shortest = std::min(shortest, (k.nodes.row(i) - c.transpose()).norm());
    const InteriorSmoothingReport rk = smooth_interior_nodes(k, only_inner(NodeFreedom::Free), Points(), ok);
    const TetQualityReport q1 = tet_quality_report(k);
    EXPECT_EQ(q1.num_inverted, 0) << trial;
    EXPECT_GE(q1.min_dihedral_deg, q0.min_dihedral_deg - 1e-12) << trial;
    EXPECT_LE((k.nodes.row(8) - c.transpose()).norm(), ok.max_displacement_fraction * shortest + 1e-12) << trial;
    EXPECT_LE(rk.max_displacement, ok.max_displacement_fraction * shortest + 1e-12) << trial;
  }
}

TEST(InteriorSmoothing, RejectsMismatchedInputs) {
  TetMesh m = cube_with_inner_node(Vec3(0.5, 0.5, 0.5));
  EXPECT_THROW(smooth_interior_nodes(m, std::vector<NodeFreedom>(3, NodeFreedom::Free), Points()), Error);
  EXPECT_THROW(smooth_interior_nodes(m, only_inner(NodeFreedom::Slide), Points::Zero(2, 3)), Error);
}

}  // namespace
}  // namespace sflsh
