// Dropping a first frame the body jumps from (the T-pose some BVH converters
// add as frame 1): detection on clips and in load_motion.
#include <gtest/gtest.h>

#include <fstream>

#include "sflsh/motion/clip_ops.hpp"
#include "sflsh/motion/load_motion.hpp"
#include "smpl_like_bvh.hpp"
#include "test_support.hpp"

namespace sflsh {
namespace {

using Quat = Eigen::Quaterniond;

/// `frames` frames at 120 fps; the left shoulder (16) turns 0.05 rad per
/// frame about z; frame 0 is replaced by a pose `jump` rad away when > 0.
MotionClip clip_with_first_frame_jump(int frames, double jump) {
  MotionClip c;
  c.name = "synthetic";
  c.fps = 120;
  for (int f = 0; f < frames; ++f) {
    std::vector<Quat> r(24, Quat::Identity());
    r[16] = Quat(Eigen::AngleAxisd(0.05 * f, Vec3::UnitZ()));
    c.rotations.push_back(r);
    c.translations.push_back(Vec3(0.01 * f, 0, 0));
  }
  if (jump > 0) c.rotations[0][18] = Quat(Eigen::AngleAxisd(jump, Vec3::UnitX()));
  return c;
}

TEST(FirstFrameJump, SmoothClipsKeepTheirFirstFrame) {
  const FirstFrameJump j = first_frame_jump(clip_with_first_frame_jump(10, 0));
  EXPECT_NEAR(j.angle, 0.05, 1e-12);
  EXPECT_EQ(j.joint, 16);
  EXPECT_NEAR(j.later_max, 0.05, 1e-12);
  EXPECT_FALSE(j.discontinuous);
  // A big but steady motion is no jump either.
  MotionClip fast = clip_with_first_frame_jump(10, 0);
  for (int f = 0; f < 10; ++f) fast.rotations[f][16] = Quat(Eigen::AngleAxisd(0.8 * f, Vec3::UnitZ()));
  EXPECT_FALSE(first_frame_jump(fast).discontinuous);
}

TEST(FirstFrameJump, DetectsAJumpOutOfFrameZero) {
  const FirstFrameJump j = first_frame_jump(clip_with_first_frame_jump(10, 1.2));
  EXPECT_EQ(j.joint, 18);
  EXPECT_NEAR(j.angle, 1.2, 1e-9);
  EXPECT_TRUE(j.discontinuous);
  // Small jumps, or too few frames to compare with, are kept.
  EXPECT_FALSE(first_frame_jump(clip_with_first_frame_jump(10, 0.3)).discontinuous);
  EXPECT_FALSE(first_frame_jump(clip_with_first_frame_jump(2, 1.2)).discontinuous);
}

TEST(FirstFrameJump, LoadMotionDropsAnAddedTPoseFrame) {
  test::TempDir dir;
  const std::string path = dir.file("tpose_first.bvh");
  // Frame 0: rest (T-pose); then the left elbow is bent 70° and turns 1° per
  // frame while the root walks 1 cm per frame.
  std::ofstream(path) << test::smpl_like_bvh(8, [](int f) {
    auto v = test::rest_frame_values();
    if (f > 0) {
      v[6 + 3 * 17] = 70.0 + f;  // left elbow Z rotation, degrees
      v[2] += 1.0 * f;           // root Z, cm
    }
    return v;
  });
  MotionReport rep;
  const MotionClip clip = load_motion(path, {}, &rep);
  EXPECT_TRUE(rep.dropped_first_frame);
  EXPECT_EQ(rep.source_frames, 8);
  EXPECT_EQ(clip.num_frames(), 7);
  EXPECT_EQ(rep.first_frame_jump_joint, "left_elbow");
  EXPECT_NEAR(rep.first_frame_jump, (71.0 * M_PI / 180), 1e-6);
  EXPECT_NE(rep.describe().find("dropped the file's first frame"), std::string::npos) << rep.describe();
  EXPECT_NE(rep.to_json().find("\"dropped_first_frame\": true"), std::string::npos);
  // Root translation stays relative to the first kept frame.
  EXPECT_LT(clip.translations[0].norm(), 1e-12);
  EXPECT_GT(clip.translations[1].norm(), 1e-3);

  MotionOptions keep;
  keep.drop_first_frame_jump = false;
  MotionReport krep;
  EXPECT_EQ(load_motion(path, keep, &krep).num_frames(), 8);
  EXPECT_FALSE(krep.dropped_first_frame);
  EXPECT_NE(krep.to_json().find("\"dropped_first_frame\": false"), std::string::npos);
}

TEST(FirstFrameJump, CmuFilesLoseTheirTPoseFrame) {
  const std::string dir = test::shared_data("mocap/cmu");
  if (dir.empty()) GTEST_SKIP() << "../shared/data/mocap/cmu is absent";
  for (const char* name : {"08_10.bvh", "16_27.bvh", "09_03.bvh", "16_46.bvh", "13_32.bvh", "02_04.bvh"}) {
    MotionReport rep;
    const MotionClip clip = load_motion(dir + "/" + name, {}, &rep);
    EXPECT_TRUE(rep.dropped_first_frame) << name;
    EXPECT_EQ(clip.num_frames(), rep.source_frames - 1) << name;
    EXPECT_GT(rep.first_frame_jump, 1.0) << name;
    EXPECT_LT(rep.later_max_jump, 0.45) << name;
    // What is left starts in the motion: no further jump.
    EXPECT_FALSE(first_frame_jump(clip).discontinuous) << name;
  }
}

}  // namespace
}  // namespace sflsh
