#include <gtest/gtest.h>

#include <cmath>

#include "sflsh/core/error.hpp"
#include "sflsh/io/npz.hpp"
#include "sflsh/motion/amass.hpp"
#include "sflsh/motion/clip_ops.hpp"
#include "sflsh/motion/load_motion.hpp"
#include "sflsh/motion/retarget.hpp"
#include "test_support.hpp"

namespace sflsh {
namespace {

using Arrays = std::map<std::string, io::NpyArray>;

io::NpyArray array(std::vector<std::int64_t> shape, std::function<double(std::int64_t)> value) {
  io::NpyArray a;
  a.shape = shape;
  a.dtype = "<f8";
  std::int64_t n = 1;
  for (auto s : shape) n *= s;
  for (std::int64_t i = 0; i < n; ++i) a.data.push_back(value(i));
  return a;
}

// T frames: joint 1 (left hip) rotated 0.1*t about x, root orientation +90°
// about X (AMASS's usual "stand up in Z-up world"), trans (t, 0, 0.9).
Arrays smplh(int T, int columns = 156) {
  Arrays a;
  a["poses"] = array({T, columns}, [&](std::int64_t i) {
    const auto t = i / columns, c = i % columns;
    if (c == 0) return M_PI / 2;
    if (c == 3) return 0.1 * double(t);
    return c >= 66 ? 0.5 : 0.0;  // hand joints: must be ignored
  });
  a["trans"] = array({T, 3}, [](std::int64_t i) { return i % 3 == 0 ? double(i / 3) : i % 3 == 2 ? 0.9 : 0.0; });
  a["betas"] = array({16}, [](std::int64_t i) { return 0.1 * double(i); });
  a["mocap_framerate"] = array({}, [](std::int64_t) { return 120.0; });
  return a;
}

TEST(Amass, SmplhPosesWithYUpConversion) {
  test::TempDir dir;
  const std::string path = dir.file("walk_poses.npz");
  io::write_npz(path, smplh(4));
  AmassInfo info;
  const MotionClip clip = read_amass(path, Points(), &info);
  ASSERT_EQ(clip.num_frames(), 4);
  EXPECT_DOUBLE_EQ(clip.fps, 120);
  EXPECT_EQ(info.layout, "poses");
  EXPECT_EQ(info.rate_key, "mocap_framerate");
  EXPECT_EQ(info.betas.size(), 16);
  EXPECT_NEAR(axis_angle_from_quaternion(clip.rotations[3][1]).x(), 0.3, 1e-12);
  // Root: R_x(-90°) * R_x(+90°) = identity (upright in Y-up).
  EXPECT_NEAR(clip.rotations[2][0].angularDistance(Eigen::Quaterniond::Identity()), 0, 1e-12);
  // Hands (joints 22, 23) stay at rest and are not driven for SMPL+H input.
  EXPECT_FALSE(clip.joint_driven[22]);
  EXPECT_NEAR(clip.rotations[1][22].angularDistance(Eigen::Quaterniond::Identity()), 0, 0);
  EXPECT_NEAR(clip.rotations[1][21].angularDistance(Eigen::Quaterniond::Identity()), 0, 0);
  // Translation: the pelvis lands at P (trans + J0): Z-up height 0.9 -> Y.
  const Vec3 J0 = default_smpl_rest_joints().row(0).transpose();
  const Vec3 pelvis = clip.translations[2] + J0;
  const Vec3 expected = Eigen::AngleAxisd(-M_PI / 2, Vec3::UnitX()) * (Vec3(2, 0, 0.9) + J0);
  EXPECT_NEAR((pelvis - expected).norm(), 0, 1e-12);
  EXPECT_NEAR(expected.y(), 0.9 + J0.z(), 1e-12);

  // Plain SMPL (T by 72) drives the hands too.
  io::write_npz(path, smplh(2, 72));
  EXPECT_TRUE(read_amass(path).joint_driven[23]);
}

TEST(Amass, SmplxKeySpelling) {
  test::TempDir dir;
  Arrays a;
  const int T = 3;
  a["root_orient"] = array({T, 3}, [](std::int64_t) { return 0.0; });
  a["pose_body"] = array({T, 63}, [](std::int64_t i) { return i % 63 == 9 ? 0.2 : 0.0; });  // joint 4 x
  a["trans"] = array({T, 3}, [](std::int64_t) { return 0.0; });
  a["mocap_frame_rate"] = array({}, [](std::int64_t) { return 60.0; });
  const std::string path = dir.file("x.npz");
  io::write_npz(path, a);
  MotionReport rep;
  MotionOptions opt;
  opt.fps = 30;
  const MotionClip clip = load_motion(path, opt, &rep);
  EXPECT_EQ(rep.format, "amass");
  EXPECT_DOUBLE_EQ(rep.source_fps, 60);
  EXPECT_EQ(clip.num_frames(), 2);  // 2 frames at 60 fps = 1/30 s -> 2 at 30 fps
  EXPECT_NEAR(axis_angle_from_quaternion(clip.rotations[1][4]).x(), 0.2, 1e-12);
  // Root orient zero in Z-up = lying down in Y-up: rotation of -90° about X.
  EXPECT_NEAR(axis_angle_from_quaternion(clip.rotations[0][0]).x(), -M_PI / 2, 1e-12);
}

TEST(Amass, MissingKeysAndWrongShapesNameTheKey) {
  test::TempDir dir;
  const std::string path = dir.file("bad.npz");
  auto expect_error = [&](Arrays a, const std::string& needle) {
    io::write_npz(path, a);
    try {
      read_amass(path);
      ADD_FAILURE() << "no error for " << needle;
    } catch (const Error& e) {
      const std::string m = e.what();
      EXPECT_NE(m.find(path), std::string::npos) << m;
      EXPECT_NE(m.find(needle), std::string::npos) << m;
    }
  };
  Arrays a = smplh(3);
  a.erase("trans");
  expect_error(a, "missing key 'trans'");
  a = smplh(3);
  a.erase("mocap_framerate");
  expect_error(a, "'mocap_framerate'");
  a = smplh(3);
  a.erase("poses");
  expect_error(a, "'root_orient'");
  a = smplh(3);
  a["trans"] = array({2, 3}, [](std::int64_t) { return 0.0; });
  expect_error(a, "'trans'");
  a = smplh(3, 50);
  expect_error(a, "key 'poses' has shape (3, 50)");
  a = smplh(3);
  a["poses"].data[7] = std::nan("");
  expect_error(a, "poses");
  a.clear();
  a["root_orient"] = array({3, 3}, [](std::int64_t) { return 0.0; });
  a["pose_body"] = array({3, 60}, [](std::int64_t) { return 0.0; });
  a["trans"] = array({3, 3}, [](std::int64_t) { return 0.0; });
  a["mocap_frame_rate"] = array({}, [](std::int64_t) { return 60.0; });
  expect_error(a, "pose_body");
}

}  // namespace
}  // namespace sflsh
