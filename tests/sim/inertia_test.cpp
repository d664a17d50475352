// Posed points, inertia and gravity terms: skinning, finite differences in the
// tangent space (bones dynamic and prescribed).
#include <random>

#include <gtest/gtest.h>

#include "finite_difference.hpp"
#include "sflsh/sim/energies/elastic.hpp"
#include "sflsh/sim/energies/gravity.hpp"
#include "sflsh/sim/energies/inertia.hpp"
#include "synthetic_avatar.hpp"

namespace sflsh {
namespace {

Isometry random_isometry(std::mt19937& rng, double angle, double shift) {
  std::normal_distribution<double> n;
  Isometry G = Isometry::Identity();
  G.linear() = Eigen::AngleAxisd(angle * n(rng), Vec3(n(rng), n(rng), n(rng)).normalized()).toRotationMatrix();
  G.translation() = shift * Vec3(n(rng), n(rng), n(rng));
  return G;
}

Configuration random_config(const Avatar& a, std::mt19937& rng, double z_scale) {
  std::uniform_real_distribution<double> u(-z_scale, z_scale);
  Configuration q;
  for (int j = 0; j < 24; ++j) q.bones.push_back(random_isometry(rng, 0.3, 0.05));
  q.z = VecX(a.num_reduced());
  for (int i = 0; i < q.z.size(); ++i) q.z[i] = u(rng);
  return q;
}

StepContext context(const Avatar& a, bool bones_dynamic) { return test::soft_step_context(a, bones_dynamic); }

Avatar small_avatar() {
  test::SyntheticAvatarOptions o;
  o.nx = 1, o.ny = 3, o.nz = 1;
  o.handles = 5;
  o.handle_radius = 0.1;
  return test::make_synthetic_avatar(o);
}

TEST(PosedPoints, RigidMotionAndSoftDisplacement) {
  const Avatar a = small_avatar();
  const PosedPoints surf = PosedPoints::at_surface(a);
  std::mt19937 rng(1);
  Configuration q;
  const Isometry G = random_isometry(rng, 0.5, 0.2);
  q.bones.assign(24, G);
  q.z = VecX::Zero(a.num_reduced());
  // All bones equal: LBS is that rigid motion (weights sum to 1).
  const Points x = surf.world(q);
  for (int v = 0; v < surf.size(); ++v)
    EXPECT_LT((x.row(v).transpose() - G * Vec3(a.surface_rest.row(v).transpose())).norm(), 1e-12);
  // Soft displacement of a surface vertex = Σ_k W_k z_k at its node (unit barycentric here).
  q.z.setRandom();
  const Points u = surf.soft_displacement(q.z);
  for (int v = 0; v < surf.size(); ++v) {
    const int n = a.surface_nodes[v];
    Vec3 expected = Vec3::Zero();
    if (a.node_role[n] == int(NodeRole::Simulated))
      for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(a.W, n); it; ++it)
        expected += it.value() * q.z.segment<3>(3 * it.col());
    EXPECT_LT((u.row(v).transpose() - expected).norm(), 1e-12);
  }
  // Joints follow their bones.
  const Points J = posed_joints(a, q.bones);
  EXPECT_LT((J.row(3).transpose() - G * Vec3(a.joints_rest.row(3).transpose())).norm(), 1e-12);
}

TEST(Inertia, GradientMatchesFiniteDifferences) {
  const Avatar a = small_avatar();
  InertiaTerm term(a);
  std::mt19937 rng(2);
  for (bool dynamic : {true, false}) {
    StepContext ctx = context(a, dynamic);
    ctx.q_prev = random_config(a, rng, 0.003);
    ctx.q_prev2 = random_config(a, rng, 0.003);
    const auto cache_term = begin_term_step(term, ctx);
    const Configuration q = random_config(a, rng, 0.003);
    const auto d = test::analytic(term, ctx, q);
    const VecX g_fd = test::fd_gradient(term, ctx, q, 1e-6);
    EXPECT_LT((d.grad - g_fd).norm(), 1e-6 * d.grad.norm()) << "bones dynamic " << dynamic;
  }
}

TEST(Inertia, GaussNewtonHessianIsExactAtThePrediction) {
  // At x(q) = x* the residual vanishes and the Gauss–Newton Hessian is the Hessian.
  const Avatar a = small_avatar();
  InertiaTerm term(a);
  std::mt19937 rng(3);
  for (bool dynamic : {true, false}) {
    StepContext ctx = context(a, dynamic);
    const Configuration q = random_config(a, rng, 0.003);
    ctx.q_prev = ctx.q_prev2 = q;
    const auto cache_term = begin_term_step(term, ctx);
    const auto d = test::analytic(term, ctx, q);
    EXPECT_LT(d.value, 1e-20);
    EXPECT_LT(test::hessian_fd_error(term, ctx, q, d.hess, 1e-4, 6, rng), 1e-6) << "bones dynamic " << dynamic;
  }
  // In kinematic mode x is linear in z: Gauss–Newton is exact everywhere.
  StepContext ctx = context(a, false);
  ctx.q_prev = random_config(a, rng, 0.003);
  ctx.q_prev2 = random_config(a, rng, 0.003);
  const auto cache_term = begin_term_step(term, ctx);
  const Configuration q = random_config(a, rng, 0.003);
  const auto d = test::analytic(term, ctx, q);
  EXPECT_LT(test::hessian_fd_error(term, ctx, q, d.hess, 1e-4, 6, rng), 1e-6);
}

TEST(Inertia, MassIsTheBodyMass) {
  const Avatar a = small_avatar();
  const InertiaTerm term(a);
  double expected = 0;  // Σ_t ρ_t V_t
  for (int t = 0; t < a.tet.num_elements(); ++t) {
    Mat3 D;
    for (int c = 1; c < 4; ++c) D.col(c - 1) = (a.tet.nodes.row(a.tet.elements(t, c)) - a.tet.nodes.row(a.tet.elements(t, 0))).transpose();
    expected += tet_material(a, t).density * D.determinant() / 6;
  }
  // Lumped node cubature uses the density of one incident tet per node: equal when
  // regions agree, within the density contrast otherwise.
  EXPECT_NEAR(term.masses().sum(), expected, 0.1 * expected);
}

TEST(Gravity, GradientMatchesFiniteDifferencesAndIsTheWeight) {
  const Avatar a = small_avatar();
  const GravityTerm term(a);
  const InertiaTerm inertia(a);
  std::mt19937 rng(4);
  for (bool dynamic : {true, false}) {
    const StepContext ctx = context(a, dynamic);
    const Configuration q = random_config(a, rng, 0.003);
    const auto d = test::analytic(term, ctx, q);
    EXPECT_LT((d.grad - test::fd_gradient(term, ctx, q, 1e-6)).norm(), 1e-6 * d.grad.norm());
    EXPECT_EQ(d.hess.norm(), 0.0);
    if (dynamic) {
      // Translating every bone by v changes E by −M g·v: Σ_j ∂E/∂v_j = −M g.
      Vec3 total = Vec3::Zero();
      for (int j = 0; j < 24; ++j) total += d.grad.segment<3>(ctx.layout.bone_offset(j) + 3);
      EXPECT_LT((total + inertia.masses().sum() * ctx.gravity).norm(), 1e-9);
    }
  }
}

}  // namespace
}  // namespace sflsh
