#include "sflsh/teleop/pose_stream_filter.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace sflsh::teleop {
namespace {

PoseMessage pose(std::uint64_t seq, double t, const Vec3& p) {
  PoseMessage m;
  m.sequence = seq;
  m.sample.time = t;
  m.sample.position = p;
  m.sample.orientation = Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Vec3::UnitY()));
  m.sample.closure = 0.4;
  return m;
}

class PoseStreamFilterTest : public ::testing::Test {
 protected:
  void SetUp() override { ASSERT_FALSE(filter.check(good, &detail)) << detail; }
  // Expects `m` to be rejected for `why` with a non-empty detail, and the good pose held.
  void expect_rejected(const PoseMessage& m, RejectReason why, const std::string& fragment) {
    detail.clear();
    const auto r = filter.check(m, &detail);
    ASSERT_TRUE(r);
    EXPECT_EQ(*r, why) << to_string(*r) << ": " << detail;
    EXPECT_NE(detail.find(fragment), std::string::npos) << detail;
    ASSERT_TRUE(filter.last_good());
    EXPECT_EQ(filter.last_good()->sequence, 10u);
    EXPECT_EQ(filter.last_good()->sample.position, good.sample.position);
  }
  PoseStreamFilter filter;  // max speed 20 m/s, tolerance 1e-3
  PoseMessage good = pose(10, 1.0, Vec3(0.1, 0.2, 0.3));
  std::string detail;
};

TEST_F(PoseStreamFilterTest, AcceptsAPlausibleNextSample) {
  // 1 cm in 1 ms = 10 m/s < 20 m/s.
  const PoseMessage next = pose(11, 1.001, Vec3(0.11, 0.2, 0.3));
  EXPECT_FALSE(filter.check(next, &detail)) << detail;
  EXPECT_EQ(filter.last_good()->sequence, 11u);
}

TEST_F(PoseStreamFilterTest, NonFiniteValuesAreRejected) {
  PoseMessage m = pose(11, 1.001, Vec3(0.1, 0.2, 0.3));
  m.sample.position.y() = std::numeric_limits<double>::quiet_NaN();
  expect_rejected(m, RejectReason::kNonFinite, "y = ");
  m = pose(11, 1.001, Vec3(0.1, 0.2, 0.3));
  m.sample.orientation.x() = std::numeric_limits<double>::infinity();
  expect_rejected(m, RejectReason::kNonFinite, "qx");
  m = pose(11, std::numeric_limits<double>::quiet_NaN(), Vec3(0.1, 0.2, 0.3));
  expect_rejected(m, RejectReason::kNonFinite, "time");
  m = pose(11, 1.001, Vec3(0.1, 0.2, 0.3));
  m.sample.closure = -std::numeric_limits<double>::infinity();
  expect_rejected(m, RejectReason::kNonFinite, "closure");
}

TEST_F(PoseStreamFilterTest, QuaternionFarFromUnitIsRejectedAndSmallDeviationNormalized) {
  PoseMessage m = pose(11, 1.001, Vec3(0.1, 0.2, 0.3));
  m.sample.orientation.coeffs() *= 1.002;  // |q| = 1.002
  expect_rejected(m, RejectReason::kBadQuaternion, "|q| = 1.002");
  m.sample.orientation = Eigen::Quaterniond(0, 0, 0, 0);
  expect_rejected(m, RejectReason::kBadQuaternion, "|q| = 0");
  // Within tolerance: accepted, stored with unit norm.
  m = pose(11, 1.001, Vec3(0.1, 0.2, 0.3));
  m.sample.orientation = Eigen::Quaterniond(1.0005, 0, 0, 0);
  EXPECT_FALSE(filter.check(m, &detail)) << detail;
  EXPECT_DOUBLE_EQ(filter.last_good()->sample.orientation.w(), 1.0);
}

TEST_F(PoseStreamFilterTest, ClosureOutsideItsRangeIsRejected) {
  PoseMessage m = pose(11, 1.001, Vec3(0.1, 0.2, 0.3));
  m.sample.closure = -0.01;
  expect_rejected(m, RejectReason::kBadClosure, "closure = -0.01");
  m.sample.closure = 3.2;  // > pi
  expect_rejected(m, RejectReason::kBadClosure, "[0, pi]");
}

TEST_F(PoseStreamFilterTest, OutOfOrderAndDuplicateSequencesAreRejected) {
  expect_rejected(pose(9, 1.001, Vec3(0.1, 0.2, 0.3)), RejectReason::kOutOfOrder, "sequence 9 after accepted sequence 10");
  expect_rejected(pose(10, 1.001, Vec3(0.1, 0.2, 0.3)), RejectReason::kOutOfOrder, "sequence 10");
  // A gap (dropped packets) is fine.
  EXPECT_FALSE(filter.check(pose(15, 1.005, Vec3(0.1, 0.2, 0.3)), &detail)) << detail;
}

TEST_F(PoseStreamFilterTest, TimeGoingBackwardsOrStandingStillIsRejected) {
  expect_rejected(pose(11, 0.999, Vec3(0.1, 0.2, 0.3)), RejectReason::kTimeNotIncreasing, "0.999");
  expect_rejected(pose(11, 1.0, Vec3(0.1, 0.2, 0.3)), RejectReason::kTimeNotIncreasing, "not after");
}

TEST_F(PoseStreamFilterTest, AbsurdJumpIsRejectedThenAcceptedOnceBelievable) {
  // 5 cm in 1 ms = 50 m/s > 20 m/s.
  expect_rejected(pose(11, 1.001, Vec3(0.15, 0.2, 0.3)), RejectReason::kJump, "50");
  // The same place 3 ms after the held sample: 5 cm / 3 ms = 16.7 m/s, believable.
  EXPECT_FALSE(filter.check(pose(12, 1.003, Vec3(0.15, 0.2, 0.3)), &detail)) << detail;
}

TEST_F(PoseStreamFilterTest, MaxSpeedIsConfigurable) {
  PoseStreamCheckOptions o;
  o.max_speed = 5.0;
  PoseStreamFilter slow(o);
  ASSERT_FALSE(slow.check(good, &detail));
  // 1 cm in 1 ms = 10 m/s: fine for the default filter, a jump for 5 m/s.
  const auto r = slow.check(pose(11, 1.001, Vec3(0.11, 0.2, 0.3)), &detail);
  ASSERT_TRUE(r);
  EXPECT_EQ(*r, RejectReason::kJump);
}

TEST(PoseStreamCounters, DescribeListsTheNonZeroReasons) {
  PoseStreamCounters c;
  c.received = 12;
  c.accepted = 9;
  c.rejected[static_cast<int>(RejectReason::kNonFinite)] = 2;
  c.rejected[static_cast<int>(RejectReason::kJump)] = 1;
  EXPECT_EQ(c.rejected_total(), 3);
  EXPECT_EQ(c.describe(), "received 12, accepted 9, rejected 3 (non-finite 2, jump 1)");
}

}  // namespace
}  // namespace sflsh::teleop
