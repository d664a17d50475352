// builtin:torture (scene/torture_motion.hpp): random poses inside the joint
// ranges, a jump every period, deterministic per seed.
#include "sflsh/scene/torture_motion.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "sflsh/core/error.hpp"

using namespace sflsh;

namespace {

/// Rotation vector of a unit quaternion through Eigen's AngleAxis (not sflsh's rotation_log).
Vec3 rotation_vector(const Eigen::Quaterniond& q) {
  const Eigen::AngleAxisd aa(q);
  return aa.angle() * aa.axis();
}

/// A few ranges copied by hand from the table's source (radians), so that a
/// wrong table lookup or mirror shows: {joint, lower, upper}.
struct HandRange {
  int joint;
  Vec3 lower, upper;
};
const HandRange kHand[] = {
    {4, {-0.1, -0.5, -0.2}, {2.6, 0.5, 0.2}},    // left knee
    {5, {-0.1, -0.5, -0.2}, {2.6, 0.5, 0.2}},    // right knee (mirror: y, z bounds swap sign)
    {18, {-1.6, -2.6, -0.4}, {1.6, 0.1, 0.4}},   // left elbow
    {19, {-1.6, -0.1, -0.4}, {1.6, 2.6, 0.4}},   // right elbow
    {16, {-1.8, -2.0, -1.8}, {1.8, 1.0, 1.6}},   // left shoulder
    {17, {-1.8, -1.0, -1.6}, {1.8, 2.0, 1.8}},   // right shoulder
};

TEST(TortureMotion, StaysWithinTheJointLimitsAndJumpsEveryPeriod) {
  TortureOptions o;
  o.seconds = 6;
  o.fps = 60;
  o.period = 0.2;
  o.seed = 7;
  const std::vector<JointRange>& ranges = smpl_joint_ranges();
  const MotionClip clip = torture_motion(ranges, o);
  ASSERT_EQ(clip.num_frames(), 361);
  EXPECT_DOUBLE_EQ(clip.fps, 60);
  const int per = 12;  // frames per period
  Vec3 lo[24], hi[24];
  for (int j = 0; j < 24; ++j) lo[j] = hi[j] = Vec3::Zero();
  for (int i = 0; i < clip.num_frames(); ++i) {
    EXPECT_EQ(clip.translations[i], Vec3::Zero());
    EXPECT_TRUE(clip.rotations[i][0].isApprox(Eigen::Quaterniond::Identity(), 1e-15)) << i;  // the root stays
    for (int j = 1; j < 24; ++j) {
      const Vec3 t = rotation_vector(clip.rotations[i][j]);
      ASSERT_TRUE(ranges[j].limited);
      for (int c = 0; c < 3; ++c) {
        EXPECT_GE(t[c], ranges[j].lower[c] - 1e-9) << "frame " << i << " joint " << j;
        EXPECT_LE(t[c], ranges[j].upper[c] + 1e-9) << "frame " << i << " joint " << j;
      }
      lo[j] = lo[j].cwiseMin(t);
      hi[j] = hi[j].cwiseMax(t);
    }
    for (const HandRange& h : kHand) {
      const Vec3 t = rotation_vector(clip.rotations[i][h.joint]);
      EXPECT_TRUE((t.array() >= h.lower.array() - 1e-9).all() && (t.array() <= h.upper.array() + 1e-9).all())
          << "frame " << i << " joint " << h.joint << ": " << t.transpose();
    }
    // First period: the rest pose. Then: constant within a period, a jump of
    // every joint at each period's first frame.
    const int k = i / per;
    for (int j = 1; j < 24; ++j) {
      const double d = i > 0 ? clip.rotations[i][j].angularDistance(clip.rotations[i - 1][j]) : 0.0;
      if (k == 0) {
        EXPECT_LT(clip.rotations[i][j].angularDistance(Eigen::Quaterniond::Identity()), 1e-15);
      }
      if (i > 0 && i % per == 0) {
        EXPECT_GT(d, 1e-3) << "no jump at frame " << i << " (t = " << i / 60.0 << " s), joint " << j;
      } else if (i > 0) {
        EXPECT_TRUE(clip.rotations[i][j].coeffs() == clip.rotations[i - 1][j].coeffs())
            << "frame " << i << " joint " << j << " moved within a period";
      }
    }
  }
  // 29 random poses cover the ranges: every component reaches at least half
  // of the way to both of its bounds (the range is really used).
  for (int j = 1; j < 24; ++j)
    for (int c = 0; c < 3; ++c) {
      const double mid = 0.5 * (ranges[j].lower[c] + ranges[j].upper[c]);
      EXPECT_LT(lo[j][c], mid + 0.5 * (ranges[j].lower[c] - mid) + 1e-12) << "joint " << j << " axis " << c;
      EXPECT_GT(hi[j][c], mid + 0.5 * (ranges[j].upper[c] - mid) - 1e-12) << "joint " << j << " axis " << c;
    }
}

TEST(TortureMotion, IsDeterministicPerSeed) {
  TortureOptions o;
  o.seconds = 1;
  const MotionClip a = torture_motion(smpl_joint_ranges(), o), b = torture_motion(smpl_joint_ranges(), o);
  o.seed = 2;
  const MotionClip c = torture_motion(smpl_joint_ranges(), o);
  bool same = true;
  double other = 0;
  for (int i = 0; i < a.num_frames(); ++i)
    for (int j = 0; j < 24; ++j) {
      same = same && a.rotations[i][j].coeffs() == b.rotations[i][j].coeffs();  // bit-identical
      other = std::max(other, a.rotations[i][j].angularDistance(c.rotations[i][j]));
    }
  EXPECT_TRUE(same);
  EXPECT_GT(other, 0.1);
}

TEST(TortureMotion, RejectsBadOptionsAndLoadsAsBuiltin) {
  TortureOptions o;
  o.period = 0.01;  // less than a frame at 60 fps
  EXPECT_THROW(torture_motion(smpl_joint_ranges(), o), Error);
  o = TortureOptions();
  o.range_fraction = 0;
  EXPECT_THROW(torture_motion(smpl_joint_ranges(), o), Error);
  o = TortureOptions();
  o.seconds = -1;
  EXPECT_THROW(torture_motion(smpl_joint_ranges(), o), Error);
  EXPECT_THROW(torture_motion(std::vector<JointRange>(3), TortureOptions()), Error);

  MotionOptions mo;
  mo.builtin_seconds = 2;
  mo.speed = 2;
  const MotionClip clip = load_stress_motion("builtin:torture", mo);
  EXPECT_EQ(clip.name, "builtin:torture");
  EXPECT_NEAR(clip.duration(), 1.0, 1e-12);  // 2 s played twice as fast
  EXPECT_EQ(load_stress_motion("builtin:shake", mo).name, "builtin:shake");  // others: load_motion
  EXPECT_THROW(load_stress_motion("builtin:nope", mo), Error);
}

}  // namespace
