#include <gtest/gtest.h>

#include <cmath>

#include "sflsh/core/error.hpp"
#include "sflsh/motion/builtin_motions.hpp"
#include "sflsh/motion/clip_ops.hpp"

namespace sflsh {
namespace {

// Largest change of finite-difference velocity between neighbouring frames,
// over all rotation coordinates (axis-angle) and the root: for a C1 motion it
// shrinks with dt (O(dt) per step); a jump in velocity would not.
double max_velocity_jump(const MotionClip& c) {
  MatXr poses, trans;
  clip_to_smpl_params(c, &poses, &trans);
  MatXr all(poses.rows(), 75);
  all << poses, trans;
  double worst = 0;
  for (int f = 1; f + 1 < all.rows(); ++f) {
    const Eigen::RowVectorXd v0 = (all.row(f) - all.row(f - 1)) * c.fps;
    const Eigen::RowVectorXd v1 = (all.row(f + 1) - all.row(f)) * c.fps;
    worst = std::max(worst, (v1 - v0).cwiseAbs().maxCoeff());
  }
  return worst;
}

TEST(BuiltinMotions, AllAreFiniteSmoothAndStartAtRest) {
  for (const auto& name : builtin_motion_names()) {
    const MotionClip c = builtin_motion(name, 3.0, 240);
    ASSERT_NO_THROW(validate_clip(c)) << name;
    EXPECT_EQ(c.num_frames(), 721) << name;
    EXPECT_EQ(c.name, "builtin:" + name);
    // Rest pose with zero velocity at t = 0 (C1 ease-in).
    for (int j = 0; j < 24; ++j) EXPECT_NEAR(c.rotations[0][j].angularDistance(Eigen::Quaterniond::Identity()), 0, 1e-12);
    EXPECT_NEAR(c.rotations[1][16].angularDistance(c.rotations[0][16]), 0, 1e-3) << name;
    // Velocity changes per step at 240 fps stay small and halve with dt (C1).
    const double jump240 = max_velocity_jump(c);
    const double jump480 = max_velocity_jump(builtin_motion(name, 3.0, 480));
    EXPECT_LT(jump240, 2.0) << name;
    EXPECT_LT(jump480, 0.6 * jump240) << name;
  }
}

TEST(BuiltinMotions, JumpBouncesAtTwoHertz) {
  const MotionClip c = builtin_motion("jump", 4.0, 100);
  double lo = 1e9, hi = -1e9;
  int crossings = 0;
  for (int f = 100; f < c.num_frames(); ++f) {  // after the ease-in
    const double y = c.translations[f].y();
    lo = std::min(lo, y);
    hi = std::max(hi, y);
    if (f > 100 && (c.translations[f - 1].y() - 0.05) * (y - 0.05) < 0) ++crossings;
  }
  EXPECT_GE(hi - lo, 0.10);
  EXPECT_LE(hi - lo, 0.25);
  EXPECT_NEAR(crossings / 2.0 / 3.0, 2.0, 0.35);  // up-down crossings per second / 2
  // Knees bend most at the lowest root position.
  int lowest = 100;
  for (int f = 100; f < c.num_frames(); ++f)
    if (c.translations[f].y() < c.translations[lowest].y()) lowest = f;
  EXPECT_GT(c.rotations[lowest][4].angularDistance(Eigen::Quaterniond::Identity()), 0.8);
}

TEST(BuiltinMotions, ShakeIsFastLateral) {
  const MotionClip c = builtin_motion("shake", 2.0, 200);
  int crossings = 0;
  for (int f = 201; f < c.num_frames(); ++f)  // t in (1, 2] s, after the ramp
    if (c.translations[f - 1].x() * c.translations[f].x() < 0) ++crossings;
  EXPECT_NEAR(crossings / 2.0, 5.0, 0.6);  // two zero crossings per period: 5 Hz
  EXPECT_GT(c.rotations[150][3].angularDistance(Eigen::Quaterniond::Identity()), 0.02);  // spine twist
}

TEST(BuiltinMotions, UnknownNameListsKnownOnes) {
  try {
    builtin_motion("dance", 1, 30);
    FAIL();
  } catch (const Error& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("dance"), std::string::npos);
    EXPECT_NE(m.find("jump"), std::string::npos);
    EXPECT_NE(m.find("shake"), std::string::npos);
  }
  EXPECT_THROW(builtin_motion("jump", 0, 30), Error);
}

}  // namespace
}  // namespace sflsh
