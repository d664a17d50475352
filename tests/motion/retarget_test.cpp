#include <gtest/gtest.h>

#include <cmath>
#include <fstream>

#include "sflsh/body/smpl_skeleton.hpp"
#include "sflsh/core/error.hpp"
#include "sflsh/motion/bvh.hpp"
#include "sflsh/motion/load_motion.hpp"
#include "sflsh/motion/retarget.hpp"
#include "smpl_like_bvh.hpp"
#include "test_support.hpp"

namespace sflsh {
namespace {

using Quat = Eigen::Quaterniond;

SkeletonMotion from_text(const std::string& text) { return skeleton_motion_from_bvh(parse_bvh(text, "test.bvh")); }

// Column of SMPL joint j's channel c (0 = Z, 1 = Y, 2 = X rotation) in FrameValues.
int col(int j, int c) { return j == 0 ? 3 + c : 6 + 3 * (j - 1) + c; }

TEST(Retarget, SingleZRotationGivesTheSameSmplLocalRotation) {
  // Frame 1: LeftArm (SMPL left_shoulder) rotated 90° about Z; hips moved 10 cm in x.
  const std::string text = test::smpl_like_bvh(2, [](int f) {
    auto v = test::rest_frame_values();
    if (f == 1) {
      v[col(16, 0)] = 90;
      v[0] += 10;
    }
    return v;
  });
  RetargetReport rep;
  RetargetOptions opt;
  const MotionClip clip = retarget_to_smpl(from_text(text), builtin_joint_map("cmu"), opt, &rep);
  ASSERT_EQ(clip.num_frames(), 2);
  EXPECT_EQ(rep.units, "cm");  // auto-detected from the leg length
  EXPECT_NEAR(rep.avatar_scale, 1.0, 1e-9);
  EXPECT_EQ(rep.mapped.size(), 22u);
  EXPECT_EQ(rep.ignored, (std::vector<std::string>{"LeftFingerBase", "RightFingerBase"}));
  EXPECT_EQ(rep.undriven, (std::vector<std::string>{"left_hand", "right_hand"}));
  const Quat expected(Eigen::AngleAxisd(M_PI / 2, Vec3::UnitZ()));
  EXPECT_NEAR(clip.rotations[1][16].angularDistance(expected), 0, 1e-9);
  for (int j = 0; j < 24; ++j) {
    EXPECT_NEAR(clip.rotations[0][j].angularDistance(Quat::Identity()), 0, 1e-9) << j;
    if (j != 16) {
      EXPECT_NEAR(clip.rotations[1][j].angularDistance(Quat::Identity()), 0, 1e-9) << j;
    }
  }
  EXPECT_NEAR((clip.translations[1] - Vec3(0.1, 0, 0)).norm(), 0, 1e-9);
  EXPECT_NEAR(clip.translations[0].norm(), 0, 1e-12);
}

TEST(Retarget, ChildRotationsAreRelativeToTheParent) {
  // Rotating the spine (LowerBack = spine1) 30° about Y and the left collar -30°
  // about Y: spine1 local = Ry(30), the collar cancels the inherited part.
  const std::string text = test::smpl_like_bvh(1, [](int) {
    auto v = test::rest_frame_values();
    v[col(3, 1)] = 30;
    return v;
  });
  const MotionClip clip = retarget_to_smpl(from_text(text), builtin_joint_map("cmu"), RetargetOptions{});
  EXPECT_NEAR(clip.rotations[0][3].angularDistance(Quat(Eigen::AngleAxisd(M_PI / 6, Vec3::UnitY()))), 0, 1e-9);
  EXPECT_NEAR(clip.rotations[0][6].angularDistance(Quat::Identity()), 0, 1e-9);
}

TEST(Retarget, RestAlignmentOfSplayedLegs) {
  // A source whose rest legs are splayed 20° outwards (like CMU's): the frame
  // that rotates them back by -20° about Z must give straight SMPL legs.
  const Points J = default_smpl_rest_joints();
  std::string text = test::smpl_like_bvh(1, [](int) {
    auto v = test::rest_frame_values();
    v[col(1, 0)] = -20;  // left hip
    v[col(2, 0)] = 20;   // right hip
    return v;
  });
  // Splay the thigh and shin offsets in the hierarchy by rotating them 20°.
  const BvhMotion bvh = parse_bvh(text, "splay.bvh");
  SkeletonMotion sk = skeleton_motion_from_bvh(bvh);
  for (const auto& [name, angle] : {std::pair<std::string, double>{"LeftLeg", 20}, {"LeftFoot", 20},
                                    {"RightLeg", -20}, {"RightFoot", -20}}) {
    const int j = sk.find(name);
    ASSERT_GE(j, 0);
    const Eigen::AngleAxisd R(angle * M_PI / 180, Vec3::UnitZ());
    sk.rest_translations[j] = R * sk.rest_translations[j];
    sk.translations[j] = sk.rest_translations[j];
  }
  const MotionClip clip = retarget_to_smpl(sk, builtin_joint_map("cmu"), RetargetOptions{});
  for (const int hip : {1, 2}) {
    const int knee = hip + 3;
    const Vec3 e = (J.row(knee) - J.row(hip)).transpose();
    // Posed SMPL thigh direction equals the rest direction.
    EXPECT_NEAR((clip.rotations[0][hip] * e - e).norm() / e.norm(), 0, 1e-6) << hip;
  }
  // Without the counter-rotation the SMPL thigh is splayed by 20°.
  sk.rotations[sk.find("LeftUpLeg")] = Quat::Identity();
  const MotionClip splayed = retarget_to_smpl(sk, builtin_joint_map("cmu"), RetargetOptions{});
  const Vec3 e = (J.row(4) - J.row(1)).transpose();
  const double angle = std::acos((splayed.rotations[0][1] * e).normalized().dot(e.normalized()));
  EXPECT_NEAR(angle * 180 / M_PI, 20, 0.1);
}

TEST(Retarget, UnitsAndAvatarScale) {
  std::string text = test::smpl_like_bvh(2, [](int f) {
    auto v = test::rest_frame_values();
    v[1] += f * 10;  // 10 cm up
    return v;
  });
  const SkeletonMotion sk = from_text(text);
  RetargetOptions opt;
  opt.units = "m";  // wrong on purpose: scale to the avatar still makes 10 cm
  RetargetReport rep;
  const MotionClip clip = retarget_to_smpl(sk, builtin_joint_map("cmu"), opt, &rep);
  EXPECT_NEAR(rep.avatar_scale, 0.01, 1e-9);
  EXPECT_NEAR(clip.translations[1].y(), 0.1, 1e-9);
  // An avatar with legs 1.5 times as long moves 1.5 times as far.
  opt.units = "auto";
  opt.rest_joints = 1.5 * default_smpl_rest_joints();
  const MotionClip big = retarget_to_smpl(sk, builtin_joint_map("cmu"), opt, &rep);
  EXPECT_NEAR(rep.avatar_scale, 1.5, 1e-9);
  EXPECT_NEAR(big.translations[1].y(), 0.15, 1e-9);
  // Absolute root: pelvis world position = scaled file position.
  opt.rest_joints = Points();
  opt.root_from_start = false;
  const MotionClip abs = retarget_to_smpl(sk, builtin_joint_map("cmu"), opt);
  EXPECT_NEAR(abs.translations[0].norm(), 0, 1e-9);  // file hips sit at SMPL's J0
  EXPECT_THROW(metres_per_unit("furlong"), Error);
}

TEST(Retarget, UnmappedSkeletonAndJointMapFiles) {
  const std::string tiny = test::source_dir() + "/tests/data/motion/tiny.bvh";
  // tiny.bvh uses CMU names: Hips/Spine/LeftUpLeg/LeftLeg map, the rest stays at rest.
  MotionReport rep;
  load_motion(tiny, {}, &rep);
  EXPECT_EQ(rep.mapped.size(), 4u);
  EXPECT_EQ(rep.undriven.size(), 20u);

  test::TempDir dir;
  const std::string text = test::smpl_like_bvh(1, [](int) { return test::rest_frame_values(); });
  std::string renamed = text;
  for (size_t p; (p = renamed.find("Hips")) != std::string::npos;) renamed.replace(p, 4, "Root");
  const std::string path = dir.file("renamed.bvh");
  std::ofstream(path) << renamed;
  try {
    load_motion(path);
    FAIL();
  } catch (const Error& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find(path), std::string::npos) << m;
    EXPECT_NE(m.find("no joint maps to SMPL 'pelvis'"), std::string::npos) << m;
    EXPECT_NE(m.find("Root"), std::string::npos) << m;
  }
  // A joint map file fixes it.
  const std::string map = dir.file("map.txt");
  std::ofstream(map) << "# file joint -> SMPL joint\nRoot pelvis\nLeftUpLeg left_hip   # thigh\n\nLeftLeg left_knee\n";
  MotionOptions o;
  o.joint_map = map;
  load_motion(path, o, &rep);
  EXPECT_EQ(rep.mapped.size(), 3u);
  EXPECT_EQ(rep.mapped[0], "Root -> pelvis");
  EXPECT_FALSE(rep.ignored.empty());

  for (const auto& [content, expect] :
       {std::pair<std::string, std::string>{"Root pelvis\nLeftUpLeg lefthip\n", ":2: unknown SMPL joint 'lefthip'"},
        {"Root\n", ":1: expected 'source_joint smpl_joint'"},
        {"Root pelvis\nHips pelvis\n", ":2: SMPL joint 'pelvis' is the target of two joints"},
        {"Root pelvis extra\n", ":1: expected two names"}}) {
    std::ofstream(map) << content;
    try {
      read_joint_map(map);
      ADD_FAILURE() << content;
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(map + expect), std::string::npos) << e.what();
    }
  }
  // A map contradicting the hierarchy.
  std::ofstream(map) << "Root pelvis\nLeftLeg left_hip\nLeftUpLeg left_knee\n";
  o.joint_map = map;
  EXPECT_THROW(load_motion(path, o), Error);
}

TEST(Retarget, CmuFilesMapAllBodyJoints) {
  const std::string dir = test::shared_data("mocap/cmu");
  if (dir.empty()) GTEST_SKIP() << "../shared/data/mocap/cmu is absent";
  const std::vector<std::pair<std::string, int>> files = {{"08_10.bvh", 276}, {"16_27.bvh", 244}, {"09_03.bvh", 129},
                                                          {"16_46.bvh", 137}, {"13_32.bvh", 337}, {"02_04.bvh", 484}};
  MotionOptions keep_tpose;  // frame 0 (CMU's added T-pose) checks the rest alignment
  keep_tpose.drop_first_frame_jump = false;
  for (const auto& [name, frames] : files) {
    MotionReport rep;
    const MotionClip clip = load_motion(dir + "/" + name, keep_tpose, &rep);
    EXPECT_EQ(rep.source_frames, frames) << name;
    EXPECT_NEAR(rep.source_fps, 120, 0.01) << name;
    EXPECT_EQ(rep.joint_map, "cmu");
    EXPECT_EQ(rep.units, "cmu") << name;
    EXPECT_NEAR(rep.avatar_scale, 1.0, 0.15) << name;
    int body = 0;
    for (int j = 0; j < 22; ++j) body += clip.joint_driven[j];
    EXPECT_EQ(body, 22) << name;
    // Frame 0 is CMU's T-pose: SMPL thighs and shins nearly vertical,
    // upper arms nearly horizontal.
    const BodyPose p = clip.sample(0);
    EXPECT_LT(p.axis_angle.row(4).norm(), 0.35) << name;
    EXPECT_LT(p.axis_angle.row(1).norm(), 0.35) << name;
    for (int f = 0; f < clip.num_frames(); ++f) ASSERT_TRUE(clip.translations[f].allFinite());
    // Root moves a plausible distance (metres).
    EXPECT_LT(clip.translations.back().norm(), 10.0) << name;
  }
  // Cross-check: the same file read through assimp retargets alike.
  MotionOptions via;
  via.bvh_via_assimp = true;
  const MotionClip a = load_motion(dir + "/08_10.bvh"), b = load_motion(dir + "/08_10.bvh", via);
  ASSERT_EQ(a.num_frames(), b.num_frames());
  double worst = 0, worst_t = 0;
  for (int f = 0; f < a.num_frames(); ++f) {
    for (int j = 0; j < 24; ++j) worst = std::max(worst, a.rotations[f][j].angularDistance(b.rotations[f][j]));
    worst_t = std::max(worst_t, (a.translations[f] - b.translations[f]).norm());
  }
  EXPECT_LT(worst, 1e-4);
  EXPECT_LT(worst_t, 1e-4);
}

}  // namespace
}  // namespace sflsh
