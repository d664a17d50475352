// PoseRamp: a live device takes over a tool without a jump. Values by hand:
// the tool at rest at T0, the device's first pose D0 1 cm below and turned
// 90° about z; the commanded pose starts on the tool, is halfway (offset
// halved, the rotation offset 45°) at mid-ramp, and is the device's after it.
#include "sflsh/teleop/pose_ramp.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "sflsh/core/error.hpp"

namespace sflsh::teleop {
namespace {

Eigen::Isometry3d pose_of(const PoseSample& s) {
  Eigen::Isometry3d G = Eigen::Isometry3d::Identity();
  G.linear() = s.orientation.toRotationMatrix();
  G.translation() = s.position;
  return G;
}

PoseSample device_sample(const Vec3& p, double angle_z) {
  PoseSample s;
  s.position = p;
  s.orientation = Eigen::Quaterniond(Eigen::AngleAxisd(angle_z, Vec3::UnitZ()));
  s.closure = 0.75;
  s.time = 4.5;
  return s;
}

TEST(PoseRamp, StartsOnTheToolIsHalfwayAtMidRampAndOnTheDeviceAfter) {
  Eigen::Isometry3d tool = Eigen::Isometry3d::Identity();
  tool.translation() = Vec3(0.0, 0.045, 0.0);
  const PoseSample d0 = device_sample(Vec3(0.0, 0.035, 0.0), M_PI / 2);
  const PoseRamp ramp(1.0, 0.5, tool, pose_of(d0));
  ASSERT_TRUE(ramp.started());

  // t0: exactly the tool (no jump), closure and time the device's.
  const PoseSample a = ramp.apply(d0, 1.0);
  EXPECT_LT((a.position - tool.translation()).norm(), 1e-15);
  EXPECT_LT(a.orientation.angularDistance(Eigen::Quaterniond::Identity()), 1e-12);
  EXPECT_EQ(a.closure, 0.75);
  EXPECT_EQ(a.time, 4.5);

  // Mid-ramp, s = 3/4 − 2/8 = 1/2: O(1/2) = (R_z(−45°), t/2) with O = T0 D0⁻¹ =
  // (R_z(−90°), t_O), t_O = 0.045 ŷ − R_z(−90°)·0.035 ŷ = (−0.035, 0.045, 0).
  const PoseSample d1 = device_sample(Vec3(0.0, 0.035, 0.0), M_PI / 2);
  EXPECT_DOUBLE_EQ(ramp.progress(1.25), 0.5);
  const PoseSample m = ramp.apply(d1, 1.25);
  const Eigen::AngleAxisd r45(-M_PI / 4, Vec3::UnitZ());
  const Vec3 expected = r45 * Vec3(0.0, 0.035, 0.0) + 0.5 * Vec3(-0.035, 0.045, 0.0);
  EXPECT_LT((m.position - expected).norm(), 1e-12) << m.position.transpose();
  EXPECT_LT(m.orientation.angularDistance(Eigen::Quaterniond(Eigen::AngleAxisd(M_PI / 4, Vec3::UnitZ()))), 1e-12);

  // After the ramp: the device's own sample, unchanged.
  const PoseSample d2 = device_sample(Vec3(0.25, 0.5, -0.125), 0.3);
  const PoseSample e = ramp.apply(d2, 1.5);
  EXPECT_EQ(e.position, d2.position);
  EXPECT_EQ(e.orientation.coeffs(), d2.orientation.coeffs());
  EXPECT_FALSE(ramp.active(1.5));
  EXPECT_TRUE(ramp.active(1.49));
}

TEST(PoseRamp, ProgressIsSmoothstepWithZeroSlopeAtBothEnds) {
  const PoseRamp ramp(2.0, 0.4, Eigen::Isometry3d::Identity(), Eigen::Isometry3d::Identity());
  EXPECT_EQ(ramp.progress(1.0), 0.0);  // before the start
  EXPECT_EQ(ramp.progress(2.0), 0.0);
  EXPECT_NEAR(ramp.progress(2.04), 3 * 0.01 - 2 * 0.001, 1e-12);  // u = 0.1
  EXPECT_NEAR(ramp.progress(2.36), 1 - (3 * 0.01 - 2 * 0.001), 1e-12);  // u = 0.9: symmetric
  EXPECT_EQ(ramp.progress(3.0), 1.0);
  // Slope at the ends ~ 0 (C¹ take-over and arrival), 1.5/duration in the middle.
  const double e = 1e-6;
  EXPECT_LT(ramp.progress(2.0 + e) / e, 1e-4);
  EXPECT_NEAR((ramp.progress(2.2 + e) - ramp.progress(2.2 - e)) / (2 * e), 1.5 / 0.4, 1e-6);
}

TEST(PoseRamp, NotStartedOrZeroDurationPassesTheSampleThrough) {
  const PoseSample d = device_sample(Vec3(0.1, 0.2, 0.3), 1.0);
  const PoseRamp idle;
  EXPECT_FALSE(idle.started());
  EXPECT_EQ(idle.apply(d, 0.0).position, d.position);
  Eigen::Isometry3d far = Eigen::Isometry3d::Identity();
  far.translation() = Vec3(1, 1, 1);
  const PoseRamp instant(0.0, 0.0, far, pose_of(d));
  EXPECT_EQ(instant.apply(d, 0.0).position, d.position);
  EXPECT_FALSE(instant.active(0.0));
}

TEST(PoseRamp, BadInputIsRefused) {
  const Eigen::Isometry3d I = Eigen::Isometry3d::Identity();
  EXPECT_THROW(PoseRamp(0.0, -0.1, I, I), Error);
  EXPECT_THROW(PoseRamp(0.0, std::nan(""), I, I), Error);
  Eigen::Isometry3d bad = I;
  bad.translation().x() = std::nan("");
  EXPECT_THROW(PoseRamp(0.0, 0.5, bad, I), Error);
}

}  // namespace
}  // namespace sflsh::teleop
