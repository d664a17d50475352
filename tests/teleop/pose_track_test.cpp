#include "sflsh/teleop/pose_track.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "test_support.hpp"

namespace sflsh::teleop {
namespace {

PoseSample sample(double t, const Vec3& p, const Eigen::Quaterniond& q, double closure) {
  PoseSample s;
  s.time = t;
  s.position = p;
  s.orientation = q;
  s.closure = closure;
  return s;
}

const Eigen::Quaterniond kIdentity = Eigen::Quaterniond::Identity();
// 90 degrees about z, written out: (cos 45°, 0, 0, sin 45°).
const Eigen::Quaterniond kQuarterTurnZ(std::sqrt(0.5), 0, 0, std::sqrt(0.5));

PoseTrack two_samples() {
  return PoseTrack({sample(1.0, Vec3(0, 0, 0), kIdentity, 0.2), sample(3.0, Vec3(2, -4, 6), kQuarterTurnZ, 1.0)});
}

TEST(PoseTrack, LinearAndSlerpAgainstHandValues) {
  const PoseSample s = two_samples().at(1.5);  // a quarter of the way
  EXPECT_EQ(s.time, 1.5);
  EXPECT_NEAR((s.position - Vec3(0.5, -1.0, 1.5)).norm(), 0.0, 1e-15);
  EXPECT_NEAR(s.closure, 0.4, 1e-15);
  // A quarter of 90° about z = 22.5°: (cos 11.25°, 0, 0, sin 11.25°).
  const double half = 11.25 * M_PI / 180.0;
  EXPECT_NEAR(s.orientation.w(), std::cos(half), 1e-14);
  EXPECT_NEAR(s.orientation.x(), 0.0, 1e-14);
  EXPECT_NEAR(s.orientation.y(), 0.0, 1e-14);
  EXPECT_NEAR(s.orientation.z(), std::sin(half), 1e-14);
}

TEST(PoseTrack, SlerpTakesTheShortArcWhateverTheQuaternionSign) {
  const Eigen::Quaterniond neg(-kQuarterTurnZ.w(), 0, 0, -kQuarterTurnZ.z());
  const PoseTrack t({sample(1.0, Vec3::Zero(), kIdentity, 0.0), sample(3.0, Vec3::Zero(), neg, 0.0)});
  const Eigen::Quaterniond q = t.at(2.0).orientation;  // 45° about z, up to sign
  EXPECT_NEAR(q.angularDistance(Eigen::Quaterniond(Eigen::AngleAxisd(M_PI / 4, Vec3::UnitZ()))), 0.0, 1e-12);
}

TEST(PoseTrack, HeldOutsideTheRangeAndExactAtSamples) {
  const PoseTrack t = two_samples();
  EXPECT_EQ(t.at(-5.0).position, Vec3(0, 0, 0));
  EXPECT_EQ(t.at(-5.0).time, -5.0);
  EXPECT_EQ(t.at(10.0).position, Vec3(2, -4, 6));
  EXPECT_EQ(t.at(10.0).closure, 1.0);
  EXPECT_EQ(t.at(3.0).position, Vec3(2, -4, 6));
  EXPECT_EQ(t.at(1.0).position, Vec3(0, 0, 0));
  EXPECT_EQ(t.start_time(), 1.0);
  EXPECT_EQ(t.end_time(), 3.0);
}

TEST(PoseTrack, FindsTheRightSegmentAmongMany) {
  std::vector<PoseSample> s;
  for (int i = 0; i < 10; ++i) s.push_back(sample(0.1 * i, Vec3(i * i, 0, 0), kIdentity, 0.0));
  const PoseTrack t(s);
  // Between samples 6 (x = 36) and 7 (x = 49), 30% of the way: 36 + 0.3 * 13 = 39.9.
  EXPECT_NEAR(t.at(0.63).position.x(), 39.9, 1e-9);
}

TEST(PoseTrack, HoldGivesTheLastSampleAtOrBeforeT) {
  const PoseTrack t = two_samples();
  EXPECT_EQ(t.at(2.999, PoseInterpolation::kHold).position, Vec3(0, 0, 0));
  EXPECT_EQ(t.at(2.999, PoseInterpolation::kHold).closure, 0.2);
  EXPECT_EQ(t.at(3.0, PoseInterpolation::kHold).position, Vec3(2, -4, 6));
  EXPECT_EQ(t.at(0.5, PoseInterpolation::kHold).position, Vec3(0, 0, 0));
}

TEST(PoseTrack, RejectsEmptyAndNonIncreasingTimes) {
  test::expect_error([] { PoseTrack t({}, "grip.csv"); }, {"grip.csv", "no pose samples"});
  test::expect_error(
      [] { PoseTrack t({sample(1.0, Vec3::Zero(), kIdentity, 0), sample(1.0, Vec3::Zero(), kIdentity, 0)}, "grip.csv"); },
      {"grip.csv", "sample 1", "strictly increasing"});
}

}  // namespace
}  // namespace sflsh::teleop
