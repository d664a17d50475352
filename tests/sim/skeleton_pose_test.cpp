#include "sflsh/sim/skeleton_pose.hpp"

#include <gtest/gtest.h>

#include "skeleton_fixture.hpp"

namespace sflsh {
namespace {

TEST(SkeletonPose, PoseToBonesToPoseRoundTrip) {
  const Avatar a = test::make_tpose_skeleton();
  std::mt19937 rng(3);
  for (int trial = 0; trial < 5; ++trial) {
    const BodyPose pose = test::random_pose(rng, 1.2);  // |θ| ≤ 2.1 rad < π: log is unique
    const std::vector<Isometry> G = bone_transforms_from_pose(a.joints_rest, a.parents, pose);
    ASSERT_EQ(G.size(), 24u);
    const BodyPose back = pose_from_bone_transforms(G, a.joints_rest, a.parents);
    EXPECT_LT((back.axis_angle - pose.axis_angle).cwiseAbs().maxCoeff(), 1e-10);
    EXPECT_LT((back.translation - pose.translation).norm(), 1e-12);
  }
}

TEST(SkeletonPose, BonesFromPoseAreConnectedAndRootIsTranslated) {
  const Avatar a = test::make_tpose_skeleton();
  std::mt19937 rng(5);
  const BodyPose pose = test::random_pose(rng, 0.8);
  const std::vector<Isometry> G = bone_transforms_from_pose(a.joints_rest, a.parents, pose);
  const Points x = joint_world_positions(G, a.joints_rest);
  for (int j = 1; j < 24; ++j) {
    const Vec3 by_parent = G[a.parents[j]] * Vec3(a.joints_rest.row(j).transpose());
    EXPECT_LT((x.row(j).transpose() - by_parent).norm(), 1e-12) << "joint " << j;
  }
  EXPECT_LT((x.row(0) - a.joints_rest.row(0) - pose.translation.transpose()).norm(), 1e-12);
}

TEST(SkeletonPose, ElbowFlexionMovesTheWristByHand) {
  // Left elbow bent 90° about −y (forearm forward, joint_limits_table.hpp's
  // sign convention): the wrist goes from elbow + (0.25, 0, 0.01) to
  // elbow + R_y(−90°)(0.25, 0, 0.01) = elbow + (−0.01, 0, 0.25).
  const Avatar a = test::make_tpose_skeleton();
  BodyPose pose;
  pose.axis_angle.row(18) << 0, -M_PI / 2, 0;
  const Points x = joint_world_positions(bone_transforms_from_pose(a.joints_rest, a.parents, pose), a.joints_rest);
  const Vec3 expected = a.joints_rest.row(18).transpose() + Vec3(-0.01, 0, 0.25);
  EXPECT_LT((x.row(20).transpose() - expected).norm(), 1e-12);
  EXPECT_LT((x.row(18) - a.joints_rest.row(18)).norm(), 1e-12);  // the elbow itself stays
}

TEST(SkeletonPose, RejectsMismatchedSkeleton) {
  const Avatar a = test::make_tpose_skeleton();
  std::vector<Isometry> G(23, Isometry::Identity());
  EXPECT_THROW(pose_from_bone_transforms(G, a.joints_rest, a.parents), Error);
  EXPECT_THROW(joint_world_positions(G, a.joints_rest), Error);
}

TEST(SkeletonPose, BonesOneStepBeforeContinueTheFirstStepsMotionBackwards) {
  // A bone moving 0.1 m along x and turning 0.3 rad about z (about the world
  // origin) over the first step was, one step earlier, 0.1 m the other way and
  // turned −0.3 rad: G(0) G(h)⁻¹ G(0) with G(0) = I. From G(0) = a turn of 0.2
  // rad about z and G(h) = a turn of 0.5 rad: one step before, 0.2 − 0.3 = −0.1 rad.
  auto turn = [](double angle, const Vec3& t) {
    Isometry G = Isometry::Identity();
    G.linear() = Eigen::AngleAxisd(angle, Vec3::UnitZ()).toRotationMatrix();
    G.translation() = t;
    return G;
  };
  const std::vector<Isometry> at0{Isometry::Identity(), turn(0.2, Vec3::Zero())};
  const std::vector<Isometry> at1{turn(0.3, Vec3(0.1, 0, 0)), turn(0.5, Vec3::Zero())};
  const std::vector<Isometry> before = bones_one_step_before(at0, at1);
  ASSERT_EQ(before.size(), 2u);
  // Δ⁻¹ of (R_z(0.3), (0.1, 0, 0)) is (R_z(−0.3), −R_z(−0.3)(0.1, 0, 0)).
  const Isometry expected0 = turn(-0.3, -(Eigen::AngleAxisd(-0.3, Vec3::UnitZ()) * Vec3(0.1, 0, 0)));
  EXPECT_LT((before[0].matrix() - expected0.matrix()).norm(), 1e-15);
  EXPECT_LT((before[1].matrix() - turn(-0.1, Vec3::Zero()).matrix()).norm(), 1e-15);
  EXPECT_THROW(bones_one_step_before(at0, {at1[0]}), Error);
}

}  // namespace
}  // namespace sflsh
