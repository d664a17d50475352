// Compact-support bounded biharmonic weights (BbwOptions::support_radius):
// each handle's weight is the bounded biharmonic function restricted to the
// nodes within a path length along the tet edges, held at 0 beyond.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <set>
#include <utility>
#include <vector>

#include "box_mesh.hpp"
#include "sflsh/asset/avatar.hpp"
#include "sflsh/basis/bounded_biharmonic.hpp"
#include "sflsh/basis/depth_fraction.hpp"
#include "sflsh/basis/handle_placement.hpp"
#include "sflsh/basis/sample_handles.hpp"
#include "sflsh/core/error.hpp"

namespace sflsh::basis {
namespace {

BbwOptions quiet(BoneCondition c, double support_radius) {
  BbwOptions o;
  o.show_progress = false;
  o.bone_condition = c;
  o.kkt_tolerance = 0.0;
  o.support_radius = support_radius;
  return o;
}

/// Weight of the middle handle of a bar [0,1]×[0,h]² with handles on the
/// faces x = 0, 0.5 and 1 (value 1 on x = 0.5, 0 on the two others).
MatX middle_weight(int nx, double support_radius) {
  const double h = 1.0 / nx;
  const TetMesh m = test::box_tet_mesh(nx, 1, 1, 1.0, h, h);
  std::vector<int> fixed;
  std::vector<double> value;
  for (int i = 0; i < m.num_nodes(); ++i) {
    const double x = m.nodes(i, 0);
    if (x < 1e-12 || x > 1.0 - 1e-12) fixed.push_back(i), value.push_back(0.0);
    if (std::abs(x - 0.5) < 1e-12) fixed.push_back(i), value.push_back(1.0);
  }
  const VecXi b = Eigen::Map<VecXi>(fixed.data(), Eigen::Index(fixed.size()));
  const MatX bc = Eigen::Map<VecX>(value.data(), Eigen::Index(value.size()));
  BbwReport rep;
  MatX w = bounded_biharmonic_qp(m, b, bc, quiet(BoneCondition::Dirichlet, support_radius), &rep);
  EXPECT_LT(rep.kkt_residual, 1e-9);
  MatX out(m.num_nodes(), 2);
  out.col(0) = m.nodes.col(0);
  out.col(1) = w.col(0);
  return out;
}

/// Max deviation of the middle weight (support radius r, 0 = none) from
/// `expected`(x); checks the bounds and the exact zeros beyond r on the way.
template <class F>
double bar_error(int nx, double r, F expected) {
  const MatX w = middle_weight(nx, r);
  double err = 0.0;
  for (Eigen::Index i = 0; i < w.rows(); ++i) {
    if (r > 0 && std::abs(w(i, 0) - 0.5) > r + 1e-9) {
      EXPECT_EQ(w(i, 1), 0.0) << "x = " << w(i, 0) << " lies outside the support";
    }
    EXPECT_GE(w(i, 1), 0.0);
    EXPECT_LE(w(i, 1), 1.0);
    err = std::max(err, std::abs(w(i, 1) - expected(w(i, 0))));
  }
  return err;
}

double cubic(double s) { return s >= 1.0 ? 0.0 : 1.0 - 3.0 * s * s + 2.0 * s * s * s; }

// By hand: on (c, c + r) the 1-D biharmonic w'''' = 0 with w(c) = 1, w'(c) = 0
// (symmetry: only the value is fixed at the handle, so w' is continuous there),
// and w(c + r) = w'(c + r) = 0 (the held nodes beyond the edge carry their own
// Laplacian rows in Q = L M⁻¹ L, which pin the slope too) is the cubic
// 1 − 3s² + 2s³, s = |x − c| / r, and exactly 0 beyond r. The discrete
// solution reaches 0 at the first held node, one edge beyond r, so it
// converges at first order (as BarConvergesToTheCubic does at the mesh
// boundary). Without a radius the other handles at distance 0.5 end it.
TEST(CompactSupport, BarHandleBetweenTwoOthersTendsToTheCubicOfItsRadius) {
  const double r = 0.3;
  auto of_radius = [&](double x) { return cubic(std::abs(x - 0.5) / r); };
  auto of_spacing = [&](double x) { return cubic(std::abs(x - 0.5) / 0.5); };
  const double e30 = bar_error(30, r, of_radius), e60 = bar_error(60, r, of_radius),
               e120 = bar_error(120, r, of_radius);
  const double full = bar_error(60, 0.0, of_spacing), apart = bar_error(120, r, of_spacing);
  std::printf("bar, handle at 0.5 between handles at 0 and 1, radius 0.3: max error vs 1-3s^2+2s^3 (s = |x-0.5|/0.3) "
              "h=1/30 %.4f, 1/60 %.4f, 1/120 %.4f; unrestricted vs s = |x-0.5|/0.5: %.4f; compact vs that: %.3f\n",
              e30, e60, e120, full, apart);
  EXPECT_LT(e120, 0.05);
  EXPECT_LT(e60, 0.6 * e30);  // first order
  EXPECT_LT(e120, 0.6 * e60);
  EXPECT_LT(full, 0.01);
  EXPECT_GT(apart, 0.2);  // the radius matters: the test tells the two apart
}

struct Slab {
  TetMesh mesh;
  VecXi role;
};

/// A 0.3×0.1×0.2 m slab of flesh on a "bone" (Dirichlet) bottom face y = 0,
/// with a skinned (Dirichlet) strip at x = 0.3.
Slab slab() {
  Slab s{test::box_tet_mesh(12, 4, 8, 0.3, 0.1, 0.2), VecXi()};
  s.role = VecXi::Zero(s.mesh.num_nodes());
  for (int i = 0; i < s.mesh.num_nodes(); ++i) {
    if (s.mesh.nodes(i, 1) < 1e-12) s.role(i) = int(NodeRole::Bone);
    else if (s.mesh.nodes(i, 0) > 0.3 - 1e-12) s.role(i) = int(NodeRole::Skinned);
  }
  return s;
}

/// Path length along the tet edges from `source` to every node, by
/// Bellman–Ford relaxation over the edge list (independent of the library's
/// Dijkstra).
VecX path_lengths(const TetMesh& m, int source) {
  std::set<std::pair<int, int>> edges;
  for (int e = 0; e < m.num_elements(); ++e)
    for (int a = 0; a < 4; ++a)
      for (int b = 0; b < 4; ++b)
        if (a != b) edges.emplace(m.elements(e, a), m.elements(e, b));
  VecX d = VecX::Constant(m.num_nodes(), std::numeric_limits<double>::infinity());
  d(source) = 0.0;
  for (bool changed = true; changed;) {
    changed = false;
    for (const auto& [i, j] : edges) {
      const double dj = d(i) + (m.nodes.row(i) - m.nodes.row(j)).norm();
      if (dj < d(j) - 1e-15) d(j) = dj, changed = true;
    }
  }
  return d;
}

void check_compact_basis(BoneCondition condition) {
  const Slab s = slab();
  const int K = 8;
  const double radius = 0.15;
  const HandleSet hs = select_handles(s.mesh, s.role, K);
  BbwReport rep, rep_full;
  const auto W = bounded_biharmonic_weights(s.mesh, s.role, hs.nodes, quiet(condition, radius), &rep);
  const auto W_full = bounded_biharmonic_weights(s.mesh, s.role, hs.nodes, quiet(condition, 0.0), &rep_full);
  std::printf("%s\n", rep.summary().c_str());
  const MatX Wd = MatX(W);
  // Bounds of the weights and of the bone complement.
  EXPECT_GE(Wd.minCoeff(), 0.0);
  EXPECT_LE(Wd.maxCoeff(), 1.0);
  const VecX sums = Wd.rowwise().sum();
  EXPECT_LE(sums.maxCoeff(), 1.0 + 1e-12);
  const VecX wb = bone_weight(W);
  EXPECT_GE(wb.minCoeff(), 0.0);
  EXPECT_LE(wb.maxCoeff(), 1.0);
  // Exactly zero outside each support; every handle reaches some node besides its own.
  for (int k = 0; k < K; ++k) {
    const VecX d = path_lengths(s.mesh, hs.nodes(k));
    int inside = 0;
    for (int i = 0; i < s.mesh.num_nodes(); ++i) {
      if (d(i) > radius * (1 + 1e-12)) {
        EXPECT_EQ(Wd(i, k), 0.0) << "handle " << k << " node " << i << " at path length " << d(i);
      }
      inside += d(i) <= radius && Wd(i, k) > 0.0;
    }
    EXPECT_GT(inside, 1) << "handle " << k;
    // At its own node a handle's row is e_k (Dirichlet) or b·e_k (DepthBlend, b the depth fraction).
    const double at_handle = condition == BoneCondition::DepthBlend ? depth_fraction(s.mesh, s.role)(hs.nodes(k)) : 1.0;
    for (int l = 0; l < K; ++l) EXPECT_EQ(Wd(hs.nodes(k), l), l == k ? at_handle : 0.0) << "handle " << k << " col " << l;
  }
  // Dirichlet nodes stay at 0.
  for (int i = 0; i < s.mesh.num_nodes(); ++i)
    if (s.role(i) != 0) {
      EXPECT_EQ(Wd.row(i).lpNorm<Eigen::Infinity>(), 0.0) << "Dirichlet node " << i;
    }
  // Partition of unity with the bone complement everywhere; with DepthBlend the
  // handles alone sum to the depth fraction wherever a handle reaches.
  EXPECT_LT((sums + wb - VecX::Ones(sums.size())).lpNorm<Eigen::Infinity>(), 1e-12);
  if (condition == BoneCondition::DepthBlend) {
    const VecX b = depth_fraction(s.mesh, s.role);
    EXPECT_EQ(rep.nodes_unreached, 0);  // the radius reaches every node of this slab
    for (int i = 0; i < s.mesh.num_nodes(); ++i)
      if (s.role(i) == 0) {
        EXPECT_NEAR(sums(i), b(i), K * BbwOptions().drop_tolerance) << "node " << i;
      }
  }
  // Smaller supports than without a radius.
  EXPECT_LT(W.nonZeros(), W_full.nonZeros());
  EXPECT_LT(rep.kkt_residual, 1e-9);
  EXPECT_EQ(rep.support_radius, radius);
  EXPECT_GT(rep.max_support_nodes, 0);
}

TEST(CompactSupport, BoundsZeroOutsideAndPartitionOfUnityDepthBlend) { check_compact_basis(BoneCondition::DepthBlend); }
TEST(CompactSupport, BoundsZeroOutsideAndPartitionOfUnityDirichlet) { check_compact_basis(BoneCondition::Dirichlet); }

// Handles per sample, counted against W's rows by hand on two tets.
TEST(CompactSupport, HandlesPerSampleCountsTheDistinctHandlesOfATetsSimulatedNodes) {
  TetMesh m;
  m.nodes.resize(5, 3);
  m.nodes << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 1, 1;
  m.elements.resize(2, 4);
  m.elements << 0, 1, 2, 3, 1, 2, 3, 4;
  VecXi role(5);
  role << 0, 0, 0, 0, 2;  // node 4 is bone: its row does not count
  Eigen::SparseMatrix<double, Eigen::RowMajor> W(5, 4);
  std::vector<Eigen::Triplet<double>> t = {{0, 3, 0.5}, {1, 0, 0.2}, {1, 1, 0.3}, {2, 2, 1.0}, {4, 3, 1.0}};
  W.setFromTriplets(t.begin(), t.end());
  Cubature c;
  c.elements.resize(2);
  c.elements << 0, 1;
  c.barycentric = MatXr::Constant(2, 4, 0.25);
  c.weights = VecX::Ones(2);
  const SampleHandleCounts n = handles_per_sample(m, W, role, c);
  EXPECT_EQ(n.samples, 2);
  EXPECT_EQ(n.max, 4);            // tet 0: handles 3 (node 0), 0 and 1 (node 1), 2 (node 2)
  EXPECT_DOUBLE_EQ(n.mean, 3.5);  // tet 1: handles 0, 1, 2; the bone node 4's handle 3 does not count
}

TEST(CompactSupport, RejectsABadRadius) {
  const Slab s = slab();
  const HandleSet hs = select_handles(s.mesh, s.role, 4);
  for (double r : {-0.1, std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity()}) {
    try {
      bounded_biharmonic_weights(s.mesh, s.role, hs.nodes, quiet(BoneCondition::DepthBlend, r));
      FAIL() << "expected an error for radius " << r;
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("support radius"), std::string::npos) << e.what();
    }
  }
}

}  // namespace
}  // namespace sflsh::basis

namespace sflsh::basis {
namespace {

// Supports sized by the handle spacing: handle k's radius is the factor times
// the distance to its nearest other handle (computed here independently).
TEST(CompactSupport, SpacingFactorGivesEachHandleItsOwnRadius) {
  const Slab s = slab();
  const int K = 8;
  const double factor = 1.5;
  const HandleSet hs = select_handles(s.mesh, s.role, K);
  BbwOptions o = quiet(BoneCondition::DepthBlend, 0.0);
  o.support_spacing_factor = factor;
  BbwReport rep;
  const MatX Wd = MatX(bounded_biharmonic_weights(s.mesh, s.role, hs.nodes, o, &rep));
  double largest = 0.0;
  int truncated = 0;  // handles whose radius cuts their unrestricted support
  const MatX Wfull = MatX(bounded_biharmonic_weights(s.mesh, s.role, hs.nodes, quiet(BoneCondition::DepthBlend, 0.0)));
  for (int k = 0; k < K; ++k) {
    double nearest = 1e300;
    for (int l = 0; l < K; ++l)
      if (l != k) nearest = std::min(nearest, (s.mesh.nodes.row(hs.nodes(k)) - s.mesh.nodes.row(hs.nodes(l))).norm());
    const double r = factor * nearest;
    largest = std::max(largest, r);
    const VecX d = path_lengths(s.mesh, hs.nodes(k));
    bool cut = false;
    for (int i = 0; i < s.mesh.num_nodes(); ++i) {
      if (d(i) > r * (1 + 1e-12)) {
        EXPECT_EQ(Wd(i, k), 0.0) << "handle " << k << " node " << i << " at " << d(i) << " beyond " << r;
        cut |= Wfull(i, k) > 0.0;
      }
    }
    truncated += cut;
  }
  EXPECT_GT(truncated, 0);  // the radii matter on this slab
  EXPECT_NEAR(rep.support_radius, largest, 1e-12);
  EXPECT_GE(Wd.minCoeff(), 0.0);
  EXPECT_LE(Wd.rowwise().sum().maxCoeff(), 1.0 + 1e-12);
  // A radius and a factor together, or a bad factor: errors.
  o.support_radius = 0.1;
  EXPECT_THROW(bounded_biharmonic_weights(s.mesh, s.role, hs.nodes, o), Error);
  o.support_radius = 0.0;
  o.support_spacing_factor = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(bounded_biharmonic_weights(s.mesh, s.role, hs.nodes, o), Error);
}

}  // namespace
}  // namespace sflsh::basis
