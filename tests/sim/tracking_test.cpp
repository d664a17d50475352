#include "sflsh/sim/energies/tracking.hpp"

#include <gtest/gtest.h>

#include "sflsh/sim/skeleton_pose.hpp"
#include "skeleton_fixture.hpp"

namespace sflsh {
namespace {

std::vector<double> stiffness_ramp() {
  std::vector<double> k(24);
  for (int j = 0; j < 24; ++j) k[j] = 10.0 + 3.0 * j;
  return k;
}

TEST(Tracking, ZeroAtTheTarget) {
  const Avatar a = test::make_tpose_skeleton();
  Tracking term(a, stiffness_ramp(), 1e4);
  std::mt19937 rng(41);
  StepContext ctx = test::skeleton_context(a, test::random_bones(rng, 0.3, 0.1));
  ctx.target_pose = test::random_pose(rng, 1.2);
  const Configuration q =
      test::bones_config(bone_transforms_from_pose(a.joints_rest, a.parents, ctx.target_pose));
  VecX g = VecX::Zero(ctx.layout.size());
  EXPECT_LT(term.evaluate(ctx, q, &g, nullptr), 1e-20);
  EXPECT_LT(g.norm(), 1e-9);
}

TEST(Tracking, SpringValues) {
  // One joint off its target by α about an axis: ½ k_j α²; root off by d: ½ k_pos |d|².
  const Avatar a = test::make_tpose_skeleton();
  const std::vector<double> k = stiffness_ramp();
  Tracking term(a, k, 1e4);
  StepContext ctx = test::skeleton_context(a, test::bones_config(std::vector<Isometry>(24, Isometry::Identity())));
  ctx.target_pose.axis_angle.row(16) << 0.1, -0.4, -1.0;
  ctx.target_pose.translation << 0.0, 0.1, 0.5;
  BodyPose pose = ctx.target_pose;
  pose.axis_angle.row(16) =
      rotation_log(rodrigues(ctx.target_pose.axis_angle.row(16).transpose()) * rodrigues(Vec3(0, 0, 0.3)))
          .transpose();  // rotated 0.3 rad further
  pose.translation += Vec3(0.01, 0.0, -0.02);
  const Configuration q = test::bones_config(bone_transforms_from_pose(a.joints_rest, a.parents, pose));
  EXPECT_NEAR(term.evaluate(ctx, q, nullptr, nullptr), 0.5 * k[16] * 0.09 + 0.5 * 1e4 * 5e-4, 1e-12);
}

TEST(Tracking, ForceLimitedRootSpringIsHuber) {
  // Root 0.05 m off its target, k = 1e4 N/m, limit F = 100 N (d = 1 cm): the
  // energy is F (|r| − d/2) = 100 · 0.045 = 4.5 J (½ k|r|² would be 12.5 J),
  // the force F along r; inside d it is the plain spring.
  const Avatar a = test::make_tpose_skeleton();
  std::vector<double> no_rot(24, 0.0);
  Tracking capped(a, no_rot, 1e4, 100.0), plain(a, no_rot, 1e4);
  StepContext ctx = test::skeleton_context(a, test::bones_config(std::vector<Isometry>(24, Isometry::Identity())));
  for (double off : {0.05, 0.004}) {
    std::vector<Isometry> G(24, Isometry::Identity());
    for (Isometry& g : G) g.translation() = Vec3(0.6, 0, 0.8) * off;  // horizontal, |shift| = off
    const Configuration q = test::bones_config(G);
    const double expected = off > 0.01 ? 100.0 * (off - 0.005) : 0.5 * 1e4 * off * off;
    EXPECT_NEAR(capped.evaluate(ctx, q, nullptr, nullptr), expected, 1e-12);
    VecX g = VecX::Zero(ctx.layout.size());
    capped.evaluate(ctx, q, &g, nullptr);
    EXPECT_LT((g - test::fd_gradient(capped, ctx, q)).norm(), 1e-6 * g.norm());
    const double force = g.segment<3>(3).norm();  // ∂E/∂v of the root bone
    EXPECT_NEAR(force, off > 0.01 ? 100.0 : 1e4 * off, 1e-9);
    if (off < 0.01) EXPECT_NEAR(capped.evaluate(ctx, q, nullptr, nullptr), plain.evaluate(ctx, q, nullptr, nullptr), 1e-15);
  }
  // Along gravity the spring is not limited (the motion carries the body's
  // weight): 5 cm up costs ½ k |r|² = 12.5 J with or without the limit.
  std::vector<Isometry> G(24, Isometry::Identity());
  for (Isometry& g : G) g.translation() = Vec3(0, 0.05, 0);
  const Configuration q = test::bones_config(G);
  EXPECT_NEAR(capped.evaluate(ctx, q, nullptr, nullptr), 12.5, 1e-12);
  VecX g = VecX::Zero(ctx.layout.size());
  capped.evaluate(ctx, q, &g, nullptr);
  EXPECT_LT((g - test::fd_gradient(capped, ctx, q)).norm(), 1e-6 * g.norm());
}

TEST(Tracking, HuberSwitchesAtTheForceLimitRadius) {
  // k = 1e4 N/m, F = 100 N: the spring turns into the constant force at
  // d = F/k = 1 cm, by hand: E = ½ k r² for r <= d, F (r − d/2) beyond; at
  // 1.5 cm that is 100 · (0.015 − 0.005) = 1.0 J (the plain spring: 1.125 J).
  const Avatar a = test::make_tpose_skeleton();
  Tracking capped(a, std::vector<double>(24, 0.0), 1e4, 100.0);
  StepContext ctx = test::skeleton_context(a, test::bones_config(std::vector<Isometry>(24, Isometry::Identity())));
  for (double off : {0.0099, 0.0101, 0.015, 0.019}) {
    std::vector<Isometry> G(24, Isometry::Identity());
    for (Isometry& g : G) g.translation() = Vec3(0.8, 0, -0.6) * off;  // horizontal
    const Configuration q = test::bones_config(G);
    const double expected = off <= 0.01 ? 0.5 * 1e4 * off * off : 100.0 * (off - 0.005);
    EXPECT_NEAR(capped.evaluate(ctx, q, nullptr, nullptr), expected, 1e-12) << off;
  }
}

TEST(Tracking, DerivativesMatchFiniteDifferences) {
  const Avatar a = test::make_tpose_skeleton();
  Tracking term(a, stiffness_ramp(), 1e4);
  std::mt19937 rng(42);
  const int n = 6 * 24;
  StepContext ctx = test::skeleton_context(a, test::random_bones(rng, 0.3, 0.1));
  ctx.target_pose = test::random_pose(rng, 0.8);
  const Configuration q = test::random_bones(rng, 1.0, 0.3);
  test::expect_residual_derivatives_match(term, ctx, q, 3 * 25);

  // At the target (zero residual) Gauss–Newton is the exact Hessian.
  const Configuration q0 =
      test::bones_config(bone_transforms_from_pose(a.joints_rest, a.parents, ctx.target_pose));
  MatX H0 = MatX::Zero(n, n);
  term.evaluate(ctx, q0, nullptr, &H0);
  EXPECT_LT(test::rel_error(H0, test::fd_hessian(term, ctx, q0)), 1e-5);
}

TEST(Tracking, RejectsBadTargets) {
  const Avatar a = test::make_tpose_skeleton();
  Tracking term(a, stiffness_ramp(), 1e4);
  const Configuration rest = test::bones_config(std::vector<Isometry>(24, Isometry::Identity()));
  StepContext ctx = test::skeleton_context(a, rest);
  ctx.target_pose.axis_angle.resize(23, 3);
  EXPECT_THROW(term.evaluate(ctx, rest, nullptr, nullptr), Error);
  ctx.target_pose = BodyPose{};
  ctx.target_pose.translation.x() = std::nan("");
  EXPECT_THROW(term.evaluate(ctx, rest, nullptr, nullptr), Error);
  EXPECT_THROW(Tracking(a, std::vector<double>(24, -1.0), 1.0), Error);
}

}  // namespace
}  // namespace sflsh
