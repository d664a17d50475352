#include "sflsh/sim/energies/joint_constraint.hpp"

#include <gtest/gtest.h>

#include "sflsh/sim/skeleton_pose.hpp"
#include "skeleton_fixture.hpp"

namespace sflsh {
namespace {

TEST(JointConstraint, ZeroForAnyPoseOfTheKinematicChain) {
  const Avatar a = test::make_tpose_skeleton();
  JointConstraint term(a, 100.0, 70.0);
  std::mt19937 rng(21);
  for (int trial = 0; trial < 5; ++trial) {
    const Configuration q =
        test::bones_config(bone_transforms_from_pose(a.joints_rest, a.parents, test::random_pose(rng, 1.5)));
    const StepContext ctx = test::skeleton_context(a, q);
    VecX g = VecX::Zero(ctx.layout.size());
    EXPECT_LT(term.evaluate(ctx, q, &g, nullptr), 1e-18);
    EXPECT_LT(g.norm(), 1e-6);  // k = 2.5e7 N/m times rounding-level gaps
  }
}

TEST(JointConstraint, PenaltyOfASeparatedJoint) {
  // Moving the left hand bone by d opens one joint: E = ½ k |d|², k = ratio M / h².
  const Avatar a = test::make_tpose_skeleton();
  JointConstraint term(a, 50.0, 80.0);
  const Configuration rest = test::bones_config(std::vector<Isometry>(24, Isometry::Identity()));
  const StepContext ctx = test::skeleton_context(a, rest, 0.02);
  EXPECT_DOUBLE_EQ(term.stiffness(0.02), 50.0 * 80.0 / 4e-4);
  Configuration q = rest;
  q.bones[22].translation() = Vec3(0.0, 1e-3, 0.0);
  EXPECT_NEAR(term.evaluate(ctx, q, nullptr, nullptr), 0.5 * 1e7 * 1e-6, 1e-9);
}

TEST(JointConstraint, DerivativesMatchFiniteDifferences) {
  const Avatar a = test::make_tpose_skeleton();
  JointConstraint term(a, 100.0, 70.0);
  std::mt19937 rng(22);
  const int n = 6 * 24;
  // Unconnected random bones: gradient and residual Jacobians.
  const Configuration q = test::random_bones(rng, 1.0, 0.3);
  const StepContext ctx = test::skeleton_context(a, q);
  test::expect_residual_derivatives_match(term, ctx, q, 3 * 23);

  // Connected skeleton (zero residual): Gauss–Newton = exact Hessian.
  const Configuration q0 =
      test::bones_config(bone_transforms_from_pose(a.joints_rest, a.parents, test::random_pose(rng, 1.0)));
  MatX H0 = MatX::Zero(n, n);
  term.evaluate(ctx, q0, nullptr, &H0);
  EXPECT_LT(test::rel_error(H0, test::fd_hessian(term, ctx, q0)), 1e-5);
}

TEST(JointConstraint, InternalForcesCancel) {
  // Joint forces are internal: they sum to zero and so do their moments about
  // the origin (momentum conservation of the free-falling skeleton).
  const Avatar a = test::make_tpose_skeleton();
  JointConstraint term(a, 100.0, 70.0);
  std::mt19937 rng(23);
  const Configuration q = test::random_bones(rng, 1.0, 0.3);
  const StepContext ctx = test::skeleton_context(a, q);
  VecX g = VecX::Zero(ctx.layout.size());
  term.evaluate(ctx, q, &g, nullptr);
  Vec3 force = Vec3::Zero(), moment = Vec3::Zero();
  for (int i = 0; i < 24; ++i) {
    moment += g.segment<3>(6 * i);
    force += g.segment<3>(6 * i + 3);
  }
  EXPECT_LT(force.norm(), 1e-9 * g.norm());
  EXPECT_LT(moment.norm(), 1e-9 * g.norm());
}

}  // namespace
}  // namespace sflsh
