// The sparse factorization of the Newton system (LinearSolver::Sparse,
// sim/sparse_hessian_solve.hpp) against the dense Cholesky, and the pattern it
// analyses against the handle supports' overlaps.
#include <gtest/gtest.h>

#include <algorithm>
#include <set>
#include <utility>
#include <vector>

#include <Eigen/Cholesky>

#include "sflsh/sim/energies/elastic.hpp"
#include "sflsh/sim/energies/inertia.hpp"
#include "sflsh/sim/simulator.hpp"
#include "sflsh/sim/skeleton_terms.hpp"
#include "sflsh/sim/sparse_hessian_solve.hpp"
#include "synthetic_avatar.hpp"

namespace sflsh {
namespace {

/// An 8×6×2-cube body (4 cm cubes) with 30 hat handles of radius 4.5 cm:
/// each handle's support holds its node and the axis neighbours.
std::shared_ptr<const Avatar> small_body() {
  test::SyntheticAvatarOptions o;
  o.nx = 8, o.ny = 6, o.nz = 2;
  o.cell = 0.04;
  o.handles = 30;
  o.handle_radius = 0.045;
  return std::make_shared<const Avatar>(test::make_synthetic_avatar(o));
}

/// Unordered handle pairs (k ≥ l) whose weights are both nonzero at some
/// Simulated node of one tet: the support overlaps the elastic samples (one
/// per tet here) see. Counted from W alone.
std::set<std::pair<int, int>> support_overlaps(const Avatar& a) {
  std::set<std::pair<int, int>> pairs;
  for (int t = 0; t < a.tet.num_elements(); ++t) {
    std::set<int> h;
    for (int c = 0; c < 4; ++c) {
      const int i = a.tet.elements(t, c);
      if (a.node_role[i] != int(NodeRole::Simulated)) continue;
      for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(a.W, i); it; ++it)
        if (it.value() != 0.0) h.insert(int(it.col()));
    }
    for (int k : h)
      for (int l : h)
        if (k >= l) pairs.emplace(k, l);
  }
  return pairs;
}

VecX dense_step(const MatX& H, const VecX& g) {
  MatX A = H;
  for (Eigen::Index i = 0; i < A.rows(); ++i)
    if (A(i, i) == 0.0) A(i, i) = 1.0;
  Eigen::LLT<MatX> llt(A);
  EXPECT_EQ(llt.info(), Eigen::Success);
  return llt.solve(-g);
}

// Bones prescribed: H is the soft block, elastic (every tet a sample, no
// exact quadratic part, which integrates over cells) plus inertia (at nodes).
TEST(SparseNewton, SoftBlockPatternIsTheSupportOverlapsAndTheStepMatchesTheDenseOne) {
  const auto a = small_body();
  const ElasticTerm elastic(*a, true, false, false);
  const InertiaTerm inertia(*a);
  StepContext ctx = test::soft_step_context(*a, false);
  ctx.q_prev.bones = ctx.q_prev2.bones = identity_bones();
  ctx.q_prev.z = ctx.q_prev2.z = VecX::Zero(a->num_reduced());
  ctx.q_prev2.z.setConstant(0.001);  // moving: a nonzero gradient
  auto cache = begin_term_step(inertia, ctx);
  Configuration q = ctx.q_prev;
  q.z = VecX::LinSpaced(a->num_reduced(), -0.002, 0.003);
  const int n = a->num_reduced();
  VecX g = VecX::Zero(n);
  MatX H = MatX::Zero(n, n);
  inertia.evaluate(ctx, q, &g, &H);
  StepContext ectx = test::soft_step_context(*a, false);
  elastic.evaluate(ectx, q, &g, &H);

  const auto pairs = support_overlaps(*a);
  long expected = 0;  // lower triangle: 6 per diagonal 3×3 block, 9 per off-diagonal one
  for (const auto& [k, l] : pairs) expected += k == l ? 6 : 9;
  ASSERT_LT(expected, long(n) * (n + 1) / 2 / 2);  // sparse: less than half the lower triangle

  SparseHessianSolver sparse(1.0, 0.0);  // any density and cost: the small body's pattern is half full
  VecX delta;
  ASSERT_TRUE(sparse.solve(H, g, delta));
  EXPECT_EQ(sparse.pattern_nonzeros(), expected);
  EXPECT_EQ(sparse.analyses(), 1);
  const VecX reference = dense_step(H, g);
  EXPECT_LT((delta - reference).norm(), 1e-10 * reference.norm());

  // A second system on the same pattern is not analysed again.
  MatX H2 = 2.0 * H;
  ASSERT_TRUE(sparse.solve(H2, g, delta));
  EXPECT_EQ(sparse.analyses(), 1);
  EXPECT_LT((delta - 0.5 * reference).norm(), 1e-10 * reference.norm());

  // A term writing a dense block (a contact patch's Schur complement) widens
  // the pattern once; the step still equals the dense one.
  MatX H3 = H;
  const int m = 12;
  H3.block(0, n - m, m, m).setConstant(1e-3);
  H3.block(n - m, 0, m, m).setConstant(1e-3);
  H3.diagonal().array() += 1.0;
  ASSERT_TRUE(sparse.solve(H3, g, delta));
  EXPECT_EQ(sparse.analyses(), 2);
  EXPECT_EQ(sparse.pattern_nonzeros(), expected + m * m);
  const VecX reference3 = dense_step(H3, g);
  EXPECT_LT((delta - reference3).norm(), 1e-10 * reference3.norm());
}

// A system too dense to pay, or not positive definite, is declined (the
// Newton step then factors it densely).
TEST(SparseNewton, DeclinesADensePatternAndAnIndefiniteSystem) {
  SparseHessianSolver sparse;
  VecX delta;
  const MatX dense = MatX::Identity(20, 20) + MatX::Constant(20, 20, 0.01);
  EXPECT_FALSE(sparse.solve(dense, VecX::Ones(20), delta));
  // A tridiagonal pattern costs ~n multiply-adds against n³/3: taken, unless
  // a simplicial factorization is assumed slower than n² / 3 times the dense one.
  MatX tri = 4.0 * MatX::Identity(60, 60);
  for (int i = 0; i + 1 < 60; ++i) tri(i, i + 1) = tri(i + 1, i) = -1.0;
  SparseHessianSolver cheap, pessimist(0.3, 1e5);
  EXPECT_TRUE(cheap.solve(tri, VecX::Ones(60), delta));
  EXPECT_DOUBLE_EQ(cheap.factor_flops(), 59.0);  // one subdiagonal entry in 59 columns of L (AMD keeps a path a path)
  EXPECT_FALSE(pessimist.solve(tri, VecX::Ones(60), delta));
  MatX indefinite = MatX::Identity(20, 20);
  indefinite(3, 3) = -1.0;
  SparseHessianSolver other;
  EXPECT_FALSE(other.solve(indefinite, VecX::Ones(20), delta));
}

/// `steps` steps with dynamic bones (bones bordered on the soft block).
Configuration run(LinearSolver solver, int steps) {
  SimulatorOptions o;
  o.bones_dynamic = true;
  o.newton.linear_solver = solver;
  o.newton.sparse_always = true;  // this body's pattern is too dense to pay; the path is what is tested
  const auto a = small_body();
  const SkeletonTermsOptions skeleton;
  Simulator sim(avatar_model(a, o, &skeleton));
  for (int i = 1; i <= steps; ++i) {
    const StepReport rep = sim.step(test::synthetic_motion(*a, i * o.h, 0.03, 0.5));
    EXPECT_EQ(rep.regularization, 0.0) << "step " << i;
    EXPECT_EQ(rep.sparse_solves, solver == LinearSolver::Sparse ? rep.iterations : 0) << "step " << i;
  }
  return sim.state();
}

/// The change from the rest state (identity bones, z = 0) stacked: z, then
/// each bone's 3×4 [R − I | t] of the bones in `bones` (all when empty).
VecX change_from_rest(const Configuration& q, std::vector<int> bones = {}) {
  if (bones.empty())
    for (int j = 0; j < int(q.bones.size()); ++j) bones.push_back(j);
  VecX s(q.z.size() + 12 * Eigen::Index(bones.size()));
  s.head(q.z.size()) = q.z;
  for (size_t k = 0; k < bones.size(); ++k) {
    Eigen::Matrix<double, 3, 4> d = q.bones[bones[k]].matrix().topRows<3>();
    d.leftCols<3>() -= Mat3::Identity();
    s.segment<12>(q.z.size() + 12 * Eigen::Index(k)) = Eigen::Map<const Eigen::Matrix<double, 12, 1>>(d.data());
  }
  return s;
}

// The synthetic body's flesh hangs on pelvis, spine1 and spine2 only; the 21
// other bones carry nothing but their own small inertia (H's diagonal spans
// ~8 decades there), so any two factorizations' round-off moves those
// bones' steps by ~1e-8 relative. The soft DoFs and the flesh-carrying bones
// are well determined: there the two steps agree to 1e-10.
TEST(SparseNewton, DynamicBoneStepsEqualTheDenseOnes) {
  const std::vector<int> carrying = {0, 3, 6};
  const Configuration dense = run(LinearSolver::Dense, 1), sparse = run(LinearSolver::Sparse, 1);
  const VecX d = change_from_rest(dense, carrying), s = change_from_rest(sparse, carrying);
  ASSERT_GT(d.norm(), 0.0);
  EXPECT_LT((s - d).norm(), 1e-10 * d.norm());
  const VecX d_all = change_from_rest(dense), s_all = change_from_rest(sparse);
  EXPECT_LT((s_all - d_all).norm(), 1e-7 * d_all.norm());
  // Over ten steps the two stay together.
  const Configuration dense10 = run(LinearSolver::Dense, 10), sparse10 = run(LinearSolver::Sparse, 10);
  const VecX d10 = change_from_rest(dense10, carrying), s10 = change_from_rest(sparse10, carrying);
  EXPECT_LT((s10 - d10).norm(), 1e-8 * d10.norm());
}

}  // namespace
}  // namespace sflsh
