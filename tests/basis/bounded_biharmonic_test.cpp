#include "sflsh/basis/bounded_biharmonic.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "box_mesh.hpp"
#include "sflsh/asset/avatar.hpp"
#include "sflsh/basis/handle_placement.hpp"
#include "sflsh/fem/tet_operators.hpp"
#include "sflsh/core/error.hpp"

namespace sflsh::basis {
namespace {

// These tests check Jacobson et al.'s formulation (bones Dirichlet 0) and
// the QP solver to round-off (no early stop); the default DepthBlend basis is
// tested in depth_blend_test.cpp.
BbwOptions quiet() {
  BbwOptions o;
  o.show_progress = false;
  o.bone_condition = BoneCondition::Dirichlet;
  o.kkt_tolerance = 0.0;
  return o;
}

/// Max deviation of the biharmonic function on a bar [0,1]×[0,h]², w = 1 on
/// the face x = 0 and 0 on x = 1, from the cubic 1 − 3x² + 2x³.
double bar_error(int nx) {
  const double h = 1.0 / nx;
  const TetMesh m = test::box_tet_mesh(nx, 1, 1, 1.0, h, h);
  std::vector<int> fixed;
  std::vector<double> value;
  for (int i = 0; i < m.num_nodes(); ++i) {
    if (m.nodes(i, 0) < 1e-12) fixed.push_back(i), value.push_back(1.0);
    if (m.nodes(i, 0) > 1.0 - 1e-12) fixed.push_back(i), value.push_back(0.0);
  }
  const VecXi b = Eigen::Map<VecXi>(fixed.data(), Eigen::Index(fixed.size()));
  const MatX bc = Eigen::Map<VecX>(value.data(), Eigen::Index(value.size()));
  BbwReport rep;
  const MatX w = bounded_biharmonic_qp(m, b, bc, quiet(), &rep);
  EXPECT_LT(rep.kkt_residual, 1e-9);
  double err = 0.0;
  for (int i = 0; i < m.num_nodes(); ++i) {
    const double x = m.nodes(i, 0);
    err = std::max(err, std::abs(w(i, 0) - (1.0 - 3.0 * x * x + 2.0 * x * x * x)));
  }
  return err;
}

// L M⁻¹ L with the Neumann stiffness matrix penalizes the boundary slope
// (the boundary row of M⁻¹L is ≈ 2∂w/∂n / h), so in 1-D with w(0)=1, w(1)=0
// the discrete minimizer tends to the cubic with w'(0) = w'(1) = 0, i.e.
// 1 − 3x² + 2x³, with an O(h) boundary-layer error.
TEST(BoundedBiharmonic, BarConvergesToTheCubic) {
  const double e10 = bar_error(10), e20 = bar_error(20), e40 = bar_error(40);
  std::printf("bar: max error vs 1-3x^2+2x^3: h=1/10 %.4f, 1/20 %.4f, 1/40 %.4f\n", e10, e20, e40);
  EXPECT_LT(e40, 0.002);  // the linear 1 − x would be 0.096 away
  EXPECT_LT(e20, 0.75 * e10);  // converging, at least at first order
  EXPECT_LT(e40, 0.75 * e20);
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

TEST(BoundedBiharmonic, BoundsInterpolationAndPartitionOfUnity) {
  const Slab s = slab();
  const int K = 10;
  const HandleSet hs = select_handles(s.mesh, s.role, K);
  BbwReport rep;
  const auto W = bounded_biharmonic_weights(s.mesh, s.role, hs.nodes, quiet(), &rep);
  std::printf("%s\n", rep.summary().c_str());
  ASSERT_EQ(W.rows(), s.mesh.num_nodes());
  ASSERT_EQ(W.cols(), K);
  const MatX Wd = MatX(W);
  // Bounds, handle interpolation, Dirichlet zeros.
  EXPECT_GE(Wd.minCoeff(), -1e-8);
  EXPECT_LE(Wd.maxCoeff(), 1.0 + 1e-8);
  for (int k = 0; k < K; ++k) {
    for (int j = 0; j < K; ++j) EXPECT_EQ(Wd(hs.nodes(k), j), k == j ? 1.0 : 0.0) << "handle " << k << " col " << j;
  }
  for (int i = 0; i < s.mesh.num_nodes(); ++i) {
    if (s.role(i) != 0) {
      EXPECT_EQ(Wd.row(i).lpNorm<Eigen::Infinity>(), 0.0) << "Dirichlet node " << i;
    }
  }
  // Partition of unity with the bone complement, which itself stays in [0,1].
  const VecX sums = Wd.rowwise().sum();
  EXPECT_LE(sums.maxCoeff(), 1.0 + 1e-12);
  const VecX wb = bone_weight(W);
  EXPECT_LT((sums + wb - VecX::Ones(sums.size())).lpNorm<Eigen::Infinity>(), 1e-6);
  EXPECT_LT(rep.partition_error, 1e-6);
  EXPECT_LT(rep.max_bound_violation, 1e-8);
  // Converged: the KKT residual falls to round-off.
  EXPECT_LT(rep.kkt_residual, 1e-9);
  ASSERT_GE(rep.kkt_history.size(), 2u);
  EXPECT_GT(rep.kkt_history.front(), 1e-4);  // the first local solve violates the bounds
  // Weights are smooth bumps: each has mass and is sparse-ish.
  const Eigen::RowVectorXd integrals = fem::integrate_linear(s.mesh, Wd);
  EXPECT_GT(integrals.minCoeff(), 0.0);
  EXPECT_LT(W.nonZeros(), Wd.size());
}

// Optimality checked independently of the solver's own test: no feasible
// perturbation of the QP solution lowers ½wᵀQw.
TEST(BoundedBiharmonic, NoFeasiblePerturbationLowersTheEnergy) {
  const Slab s = slab();
  const HandleSet hs = select_handles(s.mesh, s.role, 6);
  std::vector<int> fixed;
  for (int k = 0; k < 6; ++k) fixed.push_back(hs.nodes(k));
  for (int i = 0; i < s.mesh.num_nodes(); ++i)
    if (s.role(i) != 0) fixed.push_back(i);
  const VecXi b = Eigen::Map<VecXi>(fixed.data(), Eigen::Index(fixed.size()));
  MatX bc = MatX::Zero(b.size(), 1);
  bc(0, 0) = 1.0;  // handle 0's weight
  const MatX w = bounded_biharmonic_qp(s.mesh, b, bc, quiet());
  const auto L = fem::stiffness_laplacian(s.mesh);
  const VecX minv = fem::lumped_mass(s.mesh).cwiseInverse();
  auto energy = [&](const VecX& x) {
    const VecX Lx = L * x;
    return 0.5 * Lx.dot(minv.asDiagonal() * Lx);
  };
  std::vector<char> is_fixed(s.mesh.num_nodes(), 0);
  for (int i : fixed) is_fixed[i] = 1;
  const double e0 = energy(w.col(0));
  int at_zero = 0;
  for (int i = 0; i < s.mesh.num_nodes(); ++i) at_zero += !is_fixed[i] && w(i, 0) == 0.0;
  EXPECT_GT(at_zero, 0) << "the bounds should be active somewhere";
  std::srand(7);
  for (int t = 0; t < 50; ++t) {
    VecX x = w.col(0) + 1e-3 * VecX::Random(s.mesh.num_nodes());
    for (int i = 0; i < s.mesh.num_nodes(); ++i)
      if (is_fixed[i]) x(i) = w(i, 0);
    x = x.cwiseMax(0.0).cwiseMin(1.0);
    EXPECT_GE(energy(x), e0 * (1.0 - 1e-12)) << "trial " << t;
  }
}

// The handle weights themselves, before the bone complement w_bone = 1 − Σ_k w_k
// is formed (which makes "Σ W + w_bone = 1" true by construction): the QP
// solutions are recomputed here with the low-level solver, and every stored row
// must be that row divided by max(1, Σ_k w_k) — so a rescaled row sums to 1,
// an unscaled one keeps its sum. Many handles on a small slab overlap, so many
// rows need the rescale.
TEST(BoundedBiharmonic, HandleRowsArePartitionOfUnityBeforeTheBoneComplement) {
  const Slab s = slab();
  const int K = 24;
  const HandleSet hs = select_handles(s.mesh, s.role, K);
  BbwOptions o = quiet();
  o.drop_tolerance = 0.0;  // keep every entry: the comparison below is exact
  BbwReport rep;
  const MatX W = MatX(bounded_biharmonic_weights(s.mesh, s.role, hs.nodes, o, &rep));
  // Independent QP solutions: 1 at handle k, 0 at the other handles and at Dirichlet nodes.
  std::vector<int> fixed(hs.nodes.data(), hs.nodes.data() + K);
  for (int i = 0; i < s.mesh.num_nodes(); ++i)
    if (s.role(i) != 0) fixed.push_back(i);
  const VecXi b = Eigen::Map<VecXi>(fixed.data(), Eigen::Index(fixed.size()));
  MatX bc = MatX::Zero(b.size(), K);
  for (int k = 0; k < K; ++k) bc(k, k) = 1.0;
  const MatX Q = bounded_biharmonic_qp(s.mesh, b, bc, o);
  int rescaled = 0;
  double worst_rescaled_sum = 0, worst_row = 0;
  for (int i = 0; i < s.mesh.num_nodes(); ++i) {
    const double qsum = Q.row(i).sum();
    const double expected_sum = std::min(qsum, 1.0);
    if (qsum > 1.0 + 1e-9) {
      ++rescaled;
      worst_rescaled_sum = std::max(worst_rescaled_sum, std::abs(W.row(i).sum() - 1.0));
    }
    EXPECT_NEAR(W.row(i).sum(), expected_sum, 1e-9) << "node " << i << ", QP row sum " << qsum;
    worst_row = std::max(worst_row, (W.row(i) - Q.row(i) / std::max(1.0, qsum)).lpNorm<Eigen::Infinity>());
  }
  std::printf("%d of %d rows had sum > 1 (max %.4f); rescaled rows sum to 1 within %.1e\n", rescaled,
              s.mesh.num_nodes(), rep.max_sum_before_normalization, worst_rescaled_sum);
  ASSERT_GE(rescaled, 5) << "the test needs overlapping handles";
  EXPECT_EQ(rep.nodes_normalized, rescaled);
  EXPECT_LT(worst_rescaled_sum, 1e-12);
  EXPECT_LT(worst_row, 1e-9);
  // With the default drop tolerance, a rescaled row loses at most K dropped entries.
  const MatX Wdrop = MatX(bounded_biharmonic_weights(s.mesh, s.role, hs.nodes, quiet()));
  for (int i = 0; i < s.mesh.num_nodes(); ++i)
    if (Q.row(i).sum() > 1.0 + 1e-9)
      EXPECT_GE(Wdrop.row(i).sum(), 1.0 - K * BbwOptions().drop_tolerance) << "node " << i;
}

TEST(BoundedBiharmonic, RejectsBadInput) {
  const Slab s = slab();
  VecXi handles(2);
  handles << 0, 1;  // node 0 lies on the bone face
  EXPECT_THROW(bounded_biharmonic_weights(s.mesh, s.role, handles, quiet()), Error);
  const HandleSet hs = select_handles(s.mesh, s.role, 2);
  VecXi dup(2);
  dup << hs.nodes(0), hs.nodes(0);
  EXPECT_THROW(bounded_biharmonic_weights(s.mesh, s.role, dup, quiet()), Error);
  EXPECT_THROW(bounded_biharmonic_weights(s.mesh, VecXi::Zero(3), hs.nodes, quiet()), Error);
  // A floating component (no handle, no Dirichlet node) has no defined weights.
  const VecXi none = VecXi::Zero(s.mesh.num_nodes());
  VecXi b(1);
  b << hs.nodes(0);
  TetMesh two = s.mesh;
  const TetMesh other = test::box_tet_mesh(1, 1, 1, 0.01, 0.01, 0.01);
  two.nodes.conservativeResize(s.mesh.num_nodes() + other.num_nodes(), 3);
  two.nodes.bottomRows(other.num_nodes()) = other.nodes.rowwise() + Eigen::RowVector3d(1, 1, 1);
  two.elements.conservativeResize(s.mesh.num_elements() + other.num_elements(), 4);
  two.elements.bottomRows(other.num_elements()) = other.elements.array() + s.mesh.num_nodes();
  try {
    bounded_biharmonic_qp(two, b, MatX::Ones(1, 1), quiet());
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("component"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace sflsh::basis
