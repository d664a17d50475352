// Elastic and damping terms: finite differences, rest state, structure.
#include <random>

#include <Eigen/Eigenvalues>
#include <gtest/gtest.h>

#include "finite_difference.hpp"
#include "sflsh/sim/energies/damping.hpp"
#include "sflsh/sim/energies/elastic.hpp"
#include "sflsh/sim/compression_guard.hpp"
#include "sflsh/sim/linearized_stiffness.hpp"
#include "sflsh/sim/material.hpp"
#include "synthetic_avatar.hpp"

namespace sflsh {
namespace {

StepContext z_only_context(const Avatar& a) {
  StepContext ctx;
  ctx.avatar = &a;
  ctx.layout.bones_dynamic = false;
  ctx.layout.num_reduced = a.num_reduced();
  return ctx;
}

Configuration random_config(const Avatar& a, double scale, std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-scale, scale);
  Configuration q;
  q.bones = std::vector<Isometry>(24, Isometry::Identity());
  q.z = VecX(a.num_reduced());
  for (int i = 0; i < q.z.size(); ++i) q.z[i] = u(rng);
  return q;
}

TEST(Elastic, ZeroAtRestAndPositiveWhenDeformed) {
  test::SyntheticAvatarOptions o;
  o.handles = 6;
  const Avatar a = test::make_synthetic_avatar(o);
  const ElasticTerm term(a);
  const StepContext ctx = z_only_context(a);
  std::mt19937 rng(1);
  Configuration q = random_config(a, 0.0, rng);
  const auto d0 = test::analytic(term, ctx, q);
  EXPECT_EQ(d0.value, 0.0);
  EXPECT_LT(d0.grad.norm(), 1e-12);
  // The rest Hessian is PSD and has rigid translations of the whole handle set in
  // its null space only if no handle is pinned; here it is positive on any z that deforms.
  q = random_config(a, 0.003, rng);
  EXPECT_GT(term.evaluate(ctx, q, nullptr, nullptr), 0.0);
  EXPECT_GT(term.min_det(q.z), 0.0);
}

TEST(Elastic, ExactQuadraticPartEqualsTheSampledEnergyWhenEveryTetIsSampled) {
  // With one sample per tet, ½ zᵀ K z + Σ (Ψ − Ψ₂) is Σ Ψ term by term.
  test::SyntheticAvatarOptions o;
  o.handles = 6;
  const Avatar a = test::make_synthetic_avatar(o);
  const ElasticTerm split(a, true, true, false), sampled(a, true, false);  // per-tet volume: the split is exact
  const StepContext ctx = z_only_context(a);
  std::mt19937 rng(4);
  for (double scale : {0.001, 0.01}) {
    const Configuration q = random_config(a, scale, rng);
    const auto s = test::analytic(split, ctx, q), f = test::analytic(sampled, ctx, q);
    EXPECT_NEAR(s.value, f.value, 1e-10 * std::abs(f.value));
    EXPECT_LT((s.grad - f.grad).norm(), 1e-9 * f.grad.norm());
    // Both Hessians are PSD majorizers; at rest (z = 0) they are equal.
  }
  Configuration rest = random_config(a, 0.0, rng);
  EXPECT_LT((test::analytic(split, ctx, rest).hess - test::analytic(sampled, ctx, rest).hess).norm(),
            1e-9 * test::analytic(sampled, ctx, rest).hess.norm());
}

TEST(Elastic, GradientAndHessianMatchFiniteDifferences) {
  for (int handles : {0, 5}) {  // all-nodes basis and a smooth hat basis
    test::SyntheticAvatarOptions o;
    o.nx = 1, o.ny = 2, o.nz = 1;
    o.handles = handles;
    const Avatar a = test::make_synthetic_avatar(o);
    const ElasticTerm term(a, /*project_psd=*/false), projected(a);
    const StepContext ctx = z_only_context(a);
    std::mt19937 rng(2);
    for (double scale : {0.002, 0.006}) {
      const Configuration q = random_config(a, scale, rng);
      const auto d = test::analytic(term, ctx, q);
      const VecX g_fd = test::fd_gradient(term, ctx, q, 1e-7);
      EXPECT_LT((d.grad - g_fd).norm(), 1e-6 * d.grad.norm()) << "handles " << handles << " scale " << scale;
      EXPECT_LT(test::hessian_fd_error(term, ctx, q, d.hess, 1e-5, 8, rng), 1e-5)
          << "handles " << handles << " scale " << scale;
      EXPECT_LT((d.hess - d.hess.transpose()).norm(), 1e-12 * d.hess.norm());
      // The projected Hessian (what the solver uses) differs only by the clamped
      // geometric-stiffness directions, small at small strain.
      const auto p = test::analytic(projected, ctx, q);
      EXPECT_EQ(p.value, d.value);
      EXPECT_LT((p.grad - d.grad).norm(), 1e-12 * d.grad.norm());
      EXPECT_LT((p.hess - d.hess).norm(), 0.05 * d.hess.norm());
    }
  }
}

TEST(Elastic, ProjectedHessianIsPsdUnderLargeDeformation) {
  test::SyntheticAvatarOptions o;
  o.handles = 0;
  const Avatar a = test::make_synthetic_avatar(o);
  const ElasticTerm term(a);
  const StepContext ctx = z_only_context(a);
  std::mt19937 rng(3);
  Configuration q = random_config(a, 0.012, rng);  // 30% of a cell: strong compression somewhere
  if (!std::isfinite(term.evaluate(ctx, q, nullptr, nullptr))) q.z *= 0.5;
  const auto d = test::analytic(term, ctx, q);
  ASSERT_TRUE(std::isfinite(d.value));
  EXPECT_GE(Eigen::SelfAdjointEigenSolver<MatX>(d.hess).eigenvalues().minCoeff(), -1e-9 * d.hess.norm());
}

TEST(Elastic, InvertedElementGivesInfiniteEnergy) {
  test::SyntheticAvatarOptions o;
  const Avatar a = test::make_synthetic_avatar(o);
  const ElasticTerm term(a);
  const StepContext ctx = z_only_context(a);
  Configuration q;
  q.z = VecX::Zero(a.num_reduced());
  // Push one top handle down through the layer below (2 cells): its tets invert.
  int top = 0;
  for (int k = 0; k < a.num_handles(); ++k)
    if (a.handles(k, 1) > a.handles(top, 1)) top = k;
  q.z[3 * top + 1] = -2.0 * o.cell;
  EXPECT_TRUE(std::isinf(term.evaluate(ctx, q, nullptr, nullptr)));
  EXPECT_LE(term.min_det(q.z), 0.0);
}

/// The small slab (1 x 2 x 1 cells, 4 handles) of the damping tests.
Avatar damping_slab() {
  test::SyntheticAvatarOptions o;
  o.nx = 1, o.ny = 2, o.nz = 1;
  o.handles = 4;
  return test::make_synthetic_avatar(o);
}

TEST(Elastic, MeanDilatationGivesTheAveragedBulkShareBackBeyondTheCompressionOnset) {
  // W = identity and z_n = a·y_n: ∇u = a e_yᵀ in every tet, a = (0, −0.12, 0):
  // J = 0.88, past the guard's onset 0.92. A uniform strain has the same
  // averaged and per-tet volume change, so ½ zᵀKz is the same with and without
  // mean dilatation (LinearizedStiffness.HomogeneousStrainKeepsItsEnergy), and
  // the energies differ by the compression guard alone: on each sample,
  // ½ (1 − α) κ (0.92 − J)² (α = kPerTetVolumeShare, the share the averaged form
  // keeps per tet; compression_guard.hpp), times its cubature weight.
  test::SyntheticAvatarOptions o;
  o.handles = 0;
  const Avatar a = test::make_synthetic_avatar(o);
  const Vec3 dir(0.0, -0.12, 0.0);
  Configuration q;
  q.bones = std::vector<Isometry>(24, Isometry::Identity());
  q.z = VecX::Zero(a.num_reduced());
  for (int n = 0; n < a.tet.num_nodes(); ++n)
    for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(a.W, n); it; ++it)
      q.z.segment<3>(3 * it.col()) = a.tet.nodes(n, 1) * dir;
  const ElasticTerm mean(a, false, true, true), plain(a, false, true, false);
  const StepContext ctx = z_only_context(a);
  const double J = 0.88;
  double expected = 0;
  for (int k = 0; k < a.elastic.size(); ++k) {
    const int t = a.elastic.elements[k];
    const double kappa = MaterialPoint(tet_material(a, t), tet_frame(a, t)).kappa;
    expected += a.elastic.weights[k] * 0.5 * (1.0 - kPerTetVolumeShare) * kappa * (0.92 - J) * (0.92 - J);
  }
  ASSERT_GT(expected, 0);
  const double diff = mean.evaluate(ctx, q, nullptr, nullptr) - plain.evaluate(ctx, q, nullptr, nullptr);
  EXPECT_NEAR(diff, expected, 1e-6 * expected);
}

TEST(Damping, MatchesFiniteDifferencesAndVanishesAtRestVelocity) {
  const Avatar a = damping_slab();
  const ElasticTerm elastic(a);
  const DampingTerm term(a, elastic, 0.01);
  StepContext ctx = z_only_context(a);
  std::mt19937 rng(4);
  ctx.q_prev = random_config(a, 0.003, rng);
  Configuration q = ctx.q_prev;
  EXPECT_EQ(term.evaluate(ctx, q, nullptr, nullptr), 0.0);
  q = random_config(a, 0.003, rng);
  const auto d = test::analytic(term, ctx, q);
  EXPECT_GT(d.value, 0.0);
  EXPECT_LT((d.grad - test::fd_gradient(term, ctx, q, 1e-7)).norm(), 1e-6 * d.grad.norm());
  EXPECT_LT(test::hessian_fd_error(term, ctx, q, d.hess, 1e-5, 4, rng), 1e-6);
}

TEST(Damping, EnergyIsHalfBetaOverHTimesTheRestStiffness) {
  // Rayleigh damping as an incremental potential: E = ½ (β/h) Δzᵀ K0 Δz with
  // K0 the elastic Hessian at rest. K0 here by central differences of the
  // elastic gradient (not the term's own matrix); halving h doubles E.
  const Avatar a = damping_slab();
  const ElasticTerm elastic(a);
  const double beta = 0.02;
  const DampingTerm term(a, elastic, beta);
  StepContext ctx = z_only_context(a);
  ctx.h = 0.01;
  std::mt19937 rng(5);
  ctx.q_prev = random_config(a, 0.003, rng);
  const Configuration q = random_config(a, 0.003, rng);
  const int n = a.num_reduced();
  Configuration rest = q;
  rest.z = VecX::Zero(n);
  MatX K0(n, n);
  const double eps = 1e-6;
  for (int i = 0; i < n; ++i) {
    Configuration p = rest, m = rest;
    p.z[i] += eps, m.z[i] -= eps;
    VecX gp = VecX::Zero(n), gm = VecX::Zero(n);
    elastic.evaluate(ctx, p, &gp, nullptr);
    elastic.evaluate(ctx, m, &gm, nullptr);
    K0.col(i) = (gp - gm) / (2 * eps);
  }
  const VecX dz = q.z - ctx.q_prev.z;
  const double expected = 0.5 * beta / ctx.h * dz.dot(K0 * dz);
  ASSERT_GT(expected, 0.0);
  // 1e-5: the difference quotient's own error (measured 2.2e-6).
  EXPECT_NEAR(term.evaluate(ctx, q, nullptr, nullptr), expected, 1e-5 * expected);
  ctx.h = 0.005;
  EXPECT_NEAR(term.evaluate(ctx, q, nullptr, nullptr), 2 * expected, 2e-5 * expected);
}

}  // namespace
}  // namespace sflsh
