#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>

#include "sflsh/io/npz.hpp"
#include "sflsh/motion/load_motion.hpp"
#include "smpl_like_bvh.hpp"
#include "test_support.hpp"

namespace sflsh {
namespace {

TEST(MotionCli, InfoAndExport) {
  test::TempDir dir;
  const std::string bvh = dir.file("arm.bvh");
  std::ofstream(bvh) << test::smpl_like_bvh(11, [](int f) {
    auto v = test::rest_frame_values();
    v[6 + 3 * 15] = 9.0 * f;  // left_shoulder Z rotation, degrees
    return v;
  });
  std::string out;
  ASSERT_EQ(test::run_command(test::sflsh_binary() + " motion info " + bvh + " --json", &out), 0) << out;
  EXPECT_NE(out.find("\"frames\": 11"), std::string::npos) << out;
  EXPECT_NE(out.find("\"LeftArm -> left_shoulder\""), std::string::npos) << out;

  const std::string npz = dir.file("poses.npz");
  ASSERT_EQ(test::run_command(test::sflsh_binary() + " motion export " + bvh + " --fps 50 --out " + npz, &out), 0)
      << out;
  const auto arrays = io::read_npz(npz);
  const auto& poses = arrays.at("poses");
  ASSERT_EQ(poses.shape, (std::vector<std::int64_t>{6, 72}));  // 0.1 s at 50 fps
  EXPECT_EQ(arrays.at("trans").shape, (std::vector<std::int64_t>{6, 3}));
  EXPECT_DOUBLE_EQ(arrays.at("mocap_framerate").data.at(0), 50);
  // Last frame: 90° about Z on joint 16 (not the root: unaffected by Z up).
  EXPECT_NEAR(poses.data[5 * 72 + 3 * 16 + 2], M_PI / 2, 1e-9);
  // The export reads back (as AMASS) to the same clip.
  MotionOptions o;
  o.fps = 50;
  const MotionClip direct = load_motion(bvh, o);
  const MotionClip back = load_motion(npz);
  ASSERT_EQ(back.num_frames(), direct.num_frames());
  for (int f = 0; f < back.num_frames(); ++f) {
    EXPECT_NEAR((back.translations[f] - direct.translations[f]).norm(), 0, 1e-9);
    for (int j = 0; j < 24; ++j) EXPECT_NEAR(back.rotations[f][j].angularDistance(direct.rotations[f][j]), 0, 1e-9);
  }

  // Errors: one line, non-zero exit, nothing written.
  const std::string bad = dir.file("bad.bvh");
  std::ofstream(bad) << "HIERARCHY\nROOT Hips\n{\n";
  const std::string npz2 = dir.file("never.npz");
  EXPECT_NE(test::run_command(test::sflsh_binary() + " motion export " + bad + " --out " + npz2, &out), 0);
  EXPECT_NE(out.find(bad + ":"), std::string::npos) << out;
  EXPECT_EQ(std::count(out.begin(), out.end(), '\n'), 1) << out;
  EXPECT_FALSE(std::filesystem::exists(npz2));
  EXPECT_FALSE(std::filesystem::exists(npz2 + ".partial"));
}

}  // namespace
}  // namespace sflsh
