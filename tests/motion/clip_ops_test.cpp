#include <gtest/gtest.h>

#include <cmath>

#include "sflsh/core/error.hpp"
#include "sflsh/motion/clip_ops.hpp"

namespace sflsh {
namespace {

using Quat = Eigen::Quaterniond;

// Two frames: identity and a 90° rotation about Y on joint 5; root moves 1 m in x.
MotionClip two_frames() {
  MotionClip c;
  c.name = "two";
  c.fps = 10;
  c.rotations.assign(2, std::vector<Quat>(24, Quat::Identity()));
  c.rotations[1][5] = Quat(Eigen::AngleAxisd(M_PI / 2, Vec3::UnitY()));
  c.translations = {Vec3::Zero(), Vec3(1, 0, 0)};
  return c;
}

TEST(ClipOps, SampleSlerpsAtMidpoint) {
  const MotionClip c = two_frames();
  const BodyPose p = c.sample(0.05);  // halfway between frames 0 and 1
  EXPECT_NEAR(p.axis_angle(5, 1), M_PI / 4, 1e-12);
  EXPECT_NEAR(p.axis_angle.row(5).norm(), M_PI / 4, 1e-12);
  EXPECT_NEAR(p.translation.x(), 0.5, 1e-12);
  EXPECT_NEAR(p.axis_angle.row(4).norm(), 0.0, 1e-15);
  // Clamped outside [0, duration].
  EXPECT_NEAR(c.sample(-3).axis_angle(5, 1), 0.0, 1e-15);
  EXPECT_NEAR(c.sample(7).axis_angle(5, 1), M_PI / 2, 1e-12);
  EXPECT_NEAR(c.sample(7).translation.x(), 1.0, 1e-15);
}

TEST(ClipOps, ResampleTrimSpeed) {
  const MotionClip c = two_frames();
  const MotionClip r = resample(c, 40);  // 0.1 s at 40 fps: 5 frames
  ASSERT_EQ(r.num_frames(), 5);
  EXPECT_NEAR(r.duration(), 0.1, 1e-12);
  EXPECT_NEAR(axis_angle_from_quaternion(r.rotations[2][5]).y(), M_PI / 4, 1e-12);
  EXPECT_NEAR(r.translations[1].x(), 0.25, 1e-12);

  const MotionClip t = trim(r, 0.025, 0.075);
  ASSERT_EQ(t.num_frames(), 3);
  EXPECT_NEAR(t.translations[0].x(), 0.25, 1e-12);
  EXPECT_NEAR(t.translations[2].x(), 0.75, 1e-12);
  EXPECT_THROW(trim(r, 0.5, -1), Error);
  EXPECT_THROW(trim(r, 0.08, 0.02), Error);

  const MotionClip s = change_speed(c, 2);
  EXPECT_DOUBLE_EQ(s.fps, 20);
  EXPECT_NEAR(s.duration(), 0.05, 1e-12);
  EXPECT_THROW(change_speed(c, 0), Error);
  EXPECT_THROW(resample(c, -1), Error);
}

TEST(ClipOps, AxisAngleRoundTripAndParams) {
  for (const Vec3& aa : {Vec3(0.3, -0.2, 0.1), Vec3(0, 0, 3.0), Vec3(1e-9, 0, 0), Vec3::Zero().eval()}) {
    const Vec3 back = axis_angle_from_quaternion(quaternion_from_axis_angle(aa));
    EXPECT_NEAR((back - aa).norm(), 0.0, 1e-12) << aa.transpose();
  }
  MatXr poses, trans;
  clip_to_smpl_params(two_frames(), &poses, &trans);
  ASSERT_EQ(poses.rows(), 2);
  ASSERT_EQ(poses.cols(), 72);
  EXPECT_NEAR(poses(1, 16), M_PI / 2, 1e-12);  // joint 5, y
  EXPECT_NEAR(trans(1, 0), 1.0, 0);
}

TEST(ClipOps, ValidateNamesTheFrameAndJoint) {
  MotionClip c = two_frames();
  c.rotations[1][3].coeffs() << 0, 0, 0, 2;
  try {
    validate_clip(c);
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("frame 1 joint spine1"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace sflsh
