#include <gtest/gtest.h>

#include <fstream>

#include "sflsh/core/error.hpp"
#include "sflsh/motion/load_motion.hpp"
#include "smpl_like_bvh.hpp"
#include "test_support.hpp"

namespace sflsh {
namespace {

// BVH read by assimp must retarget to the same SMPL clip as the own parser:
// a cross-check of the assimp path (node tree, channels, key timing).
TEST(AssimpMotion, BvhThroughAssimpMatchesOwnParser) {
  test::TempDir dir;
  const std::string path = dir.file("cross.bvh");
  std::ofstream(path) << test::smpl_like_bvh(5, [](int f) {
    auto v = test::rest_frame_values();
    v[0] += 2.0 * f;
    v[3] = 10.0 * f;                      // root Z rotation
    v[6 + 3 * 15 + 0] = 15.0 * f;         // left shoulder Z
    v[6 + 3 * 15 + 1] = -5.0 * f;         // left shoulder Y
    v[6 + 3 * 3 + 2] = 12.0 * f;          // left knee X
    return v;
  });
  MotionOptions own, via;
  via.bvh_via_assimp = true;
  MotionReport r_own, r_via;
  const MotionClip a = load_motion(path, own, &r_own);
  const MotionClip b = load_motion(path, via, &r_via);
  EXPECT_EQ(r_via.format, "assimp");
  ASSERT_EQ(a.num_frames(), b.num_frames());
  EXPECT_NEAR(a.fps, b.fps, 1e-4);  // assimp keeps times in float
  EXPECT_EQ(r_own.mapped, r_via.mapped);
  for (int f = 0; f < a.num_frames(); ++f) {
    EXPECT_NEAR((a.translations[f] - b.translations[f]).norm(), 0, 1e-6) << f;
    for (int j = 0; j < 24; ++j)
      EXPECT_NEAR(a.rotations[f][j].angularDistance(b.rotations[f][j]), 0, 1e-6) << "frame " << f << " joint " << j;
  }
}

TEST(AssimpMotion, UnreadableFileNamesIt) {
  test::TempDir dir;
  const std::string path = dir.file("junk.fbx");
  std::ofstream(path) << "not an fbx";
  try {
    load_motion(path);
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace sflsh
