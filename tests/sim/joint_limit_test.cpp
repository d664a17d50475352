#include "sflsh/sim/energies/joint_limit.hpp"

#include <gtest/gtest.h>

#include "sflsh/sim/skeleton_pose.hpp"
#include "skeleton_fixture.hpp"

namespace sflsh {
namespace {

TEST(So3LeftJacobianInverse, MatchesTheLogOfAPerturbedRotation) {
  // log(exp(δ) exp(φ)) = φ + J_l⁻¹(φ) δ + O(δ²), across the series/closed-form
  // switch (|φ| = 1e-2) and close to π.
  std::mt19937 rng(31);
  for (double angle : {0.0, 1e-7, 0.009, 0.011, 0.5, 2.0, 3.1}) {
    const Vec3 phi = angle * test::random_vector(rng, 1.0).normalized();
    const Mat3 R = rodrigues(phi);
    const Mat3 Jinv = so3_left_jacobian_inverse(phi);
    Mat3 fd;
    const double eps = 1e-6;
    for (int k = 0; k < 3; ++k) {
      const Vec3 d = eps * Vec3::Unit(k);
      fd.col(k) = (rotation_log(rodrigues(d) * R) - rotation_log(rodrigues(-d) * R)) / (2 * eps);
    }
    EXPECT_LT((Jinv - fd).norm(), 1e-8) << "angle " << angle;
  }
}

TEST(JointLimitsTable, AnatomicalShape) {
  const std::vector<JointRange>& t = smpl_joint_ranges();
  ASSERT_EQ(t.size(), 24u);
  EXPECT_FALSE(t[0].limited);  // root is free
  for (int j = 1; j < 24; ++j) {
    EXPECT_TRUE(t[j].limited) << j;
    // The rest pose is inside every range.
    EXPECT_TRUE((t[j].lower.array() <= 0).all() && (t[j].upper.array() >= 0).all()) << j;
  }
  // Knees (4, 5) flex one way (+x) only; elbows flex forward only
  // (left −y, right +y).
  for (int k : {4, 5}) EXPECT_TRUE(t[k].lower.x() >= -0.1 && t[k].upper.x() > 2.0);
  EXPECT_TRUE(t[18].upper.y() <= 0.1 && t[18].lower.y() < -2.0);
  EXPECT_TRUE(t[19].lower.y() >= -0.1 && t[19].upper.y() > 2.0);
  // Right side is the mirror image of the left.
  for (int l : {1, 4, 7, 10, 13, 16, 18, 20, 22}) {
    EXPECT_EQ(t[l + 1].lower, Vec3(t[l].lower.x(), -t[l].upper.y(), -t[l].upper.z())) << l;
    EXPECT_EQ(t[l + 1].upper, Vec3(t[l].upper.x(), -t[l].lower.y(), -t[l].lower.z())) << l;
  }
}

std::vector<double> uniform_stiffness(double k) { return std::vector<double>(24, k); }

TEST(JointLimit, ZeroInsideAndQuadraticOutside) {
  const Avatar a = test::make_tpose_skeleton();
  const double k = 40.0;
  JointLimit term(a, smpl_joint_ranges(), uniform_stiffness(k));
  auto energy = [&](const BodyPose& pose) {
    const Configuration q = test::bones_config(bone_transforms_from_pose(a.joints_rest, a.parents, pose));
    return term.evaluate(test::skeleton_context(a, q), q, nullptr, nullptr);
  };
  BodyPose pose;
  EXPECT_EQ(energy(pose), 0.0);  // rest
  pose.axis_angle.row(4) << 1.5, 0.1, 0.0;  // knee flexed: fine
  pose.axis_angle.row(16) << 0.3, -0.5, -1.2;  // left arm down and forward: fine
  pose.translation << 0.3, 0.2, 0.0;
  pose.axis_angle.row(0) << 0.4, 2.0, 0.1;  // root: unlimited
  EXPECT_EQ(energy(pose), 0.0);
  pose.axis_angle.row(4) << -0.5, 0.1, 0.0;  // knee hyperextended by 0.4 rad
  EXPECT_NEAR(energy(pose), 0.5 * k * 0.4 * 0.4, 1e-12);
  pose.axis_angle.row(18) << 0.0, 0.3, 0.0;  // left elbow bent backwards by 0.2 rad
  EXPECT_NEAR(energy(pose), 0.5 * k * (0.16 + 0.04), 1e-12);
}

TEST(JointLimit, DerivativesMatchFiniteDifferences) {
  const Avatar a = test::make_tpose_skeleton();
  std::vector<double> k(24);
  for (int j = 0; j < 24; ++j) k[j] = 5.0 + j;
  JointLimit term(a, smpl_joint_ranges(), k);
  std::mt19937 rng(32);
  const int n = 6 * 24;
  for (int trial = 0; trial < 3; ++trial) {
    // Unconnected bones, rotated well beyond many limits.
    const Configuration q = test::random_bones(rng, 1.3, 0.2);
    const StepContext ctx = test::skeleton_context(a, q);
    VecX g = VecX::Zero(n);
    MatX H = MatX::Zero(n, n);
    const double E = term.evaluate(ctx, q, &g, &H);
    ASSERT_GT(E, 0.0);
    EXPECT_LT(test::rel_error(g, test::fd_gradient(term, ctx, q)), 1e-6);
    VecX r;
    MatX J;
    test::stacked_residuals(term, ctx, q, r, &J);
    EXPECT_GT(r.size(), 3 * 5);
    const MatX J_fd = test::fd_residual_jacobian(term, ctx, q);
    ASSERT_EQ(J_fd.rows(), J.rows());
    EXPECT_LT(test::rel_error(J, J_fd), 1e-7);
    EXPECT_GT(test::min_eigenvalue(H), -1e-9 * H.norm());
  }
}

TEST(JointLimit, RejectsInconsistentInput) {
  const Avatar a = test::make_tpose_skeleton();
  EXPECT_THROW(JointLimit(a, smpl_joint_ranges(), std::vector<double>(23, 1.0)), Error);
  EXPECT_THROW(JointLimit(a, smpl_joint_ranges(), uniform_stiffness(-1.0)), Error);
  std::vector<JointRange> bad = smpl_joint_ranges();
  bad[4].lower.x() = 3.0;
  EXPECT_THROW(JointLimit(a, bad, uniform_stiffness(1.0)), Error);
}

}  // namespace
}  // namespace sflsh
